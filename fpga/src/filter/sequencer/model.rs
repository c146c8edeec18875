//! [`SequencerModel`]: the RTL's registers, RAMs and next-state logic, clock for clock.
//! The registers are `model/regs.rs`, the combinational signals an edge reads
//! `model/signals.rs`, the states' arms `model/states.rs`; [`SequencerModel::step`] wires
//! them with the multiplier, the divider and the memories.

use super::{SeqInputs, SeqOutputs};
use crate::common::format::exp_table;
use crate::filter::pf::{Particle, CORDIC_ATAN, PARAMS, POSE_PROGRAM};

use crate::filter::seq_state::SeqState;

mod regs;
mod signals;
mod states;

use regs::{m, sx, Regs, WritePort};
use signals::Signals;
use states::Drive;

/// The cycle-accurate model of `PfSequencer`: [`SequencerModel::step`] is one rising edge
/// (the inputs as they are before it), [`SequencerModel::outputs`] the ports after it.
#[derive(Clone, Debug)]
pub struct SequencerModel {
    r: Regs,
    pram: Vec<u32>,
    cram: Vec<u128>,
    wram: Vec<u16>,
    rf: [u64; 32],
    exp: [u16; crate::common::format::EXP_ENTRIES],
    prog: [u64; 32],
    atan: [u64; 32],
}

impl Default for SequencerModel {
    fn default() -> Self {
        Self::new()
    }
}

impl SequencerModel {
    /// After power-up: every register, RAM and the register file zero (idle, no result).
    pub fn new() -> Self {
        let mut prog = [0u64; 32];
        for (k, op) in POSE_PROGRAM.iter().enumerate() {
            prog[k] = op.encode() as u64 & m(17);
        }
        let mut atan = [0u64; 32];
        for (k, &t) in CORDIC_ATAN.iter().enumerate() {
            atan[k] = t as u64 & m(22);
        }
        SequencerModel {
            r: Regs::default(),
            pram: vec![0; 1 << 12],
            cram: vec![0; 1 << 8],
            wram: vec![0; 1 << 8],
            rf: [0; 32],
            exp: exp_table(),
            prog,
            atan,
        }
    }

    /// The state register.
    pub fn state(&self) -> SeqState {
        self.r.state
    }

    /// The state register's name in the RTL.
    pub fn state_name(&self) -> &'static str {
        self.r.state.name()
    }

    /// The configured particle count (the 9-bit `n_part` register).
    pub fn particle_count(&self) -> usize {
        self.r.n_part as usize
    }

    /// The half of the particle RAM the current iteration works on.
    pub fn half(&self) -> usize {
        self.r.half as usize
    }

    /// The first [`SequencerModel::particle_count`] particles (at most 256) of half `half`
    /// of the particle RAM, sign-extended from 24 bits.
    pub fn particles(&self, half: usize) -> Vec<Particle> {
        let n = self.particle_count().min(crate::filter::pf::MAX_PARTICLES);
        (0..n)
            .map(|i| std::array::from_fn(|d| sx(self.pram[((half & 1) << 11) | (i << 3) | d] as u64, 24) as i32))
            .collect()
    }

    /// The sigma registers (22 bits each).
    pub fn sigma(&self) -> [u32; PARAMS] {
        self.r.sigma.map(|s| s as u32)
    }

    /// The region centre registers (the configured centre until the first region update).
    pub fn centre(&self) -> Particle {
        self.r.centre.map(|c| sx(c, 24) as i32)
    }

    /// The best particle or estimate so far (the `params` output).
    pub fn best(&self) -> Particle {
        self.r.best.map(|c| sx(c, 24) as i32)
    }

    /// The last estimate.
    pub fn estimate(&self) -> Particle {
        self.r.est.map(|c| sx(c, 24) as i32)
    }

    /// The iteration in progress, from 0 (the `k` register; `iterations` counts completed).
    pub fn iteration(&self) -> u16 {
        self.r.k as u16
    }

    /// The pram write port: combinational from the state and registers.
    fn pram_port(&self) -> WritePort<u64> {
        let r = &self.r;
        let mut port = WritePort { we: false, addr: r.pa as usize, data: self.v_fix() };
        match r.state {
            SeqState::PropWrite => port.we = true,
            SeqState::CpData => {
                port.we = true;
                port.addr = ((!r.half as usize) << 11) | (((r.j & m(8)) as usize) << 3) | r.pd as usize;
                port.data = r.pram_q;
            }
            _ => {}
        }
        port
    }

    fn sel(&self, v: &[u64; PARAMS]) -> u64 {
        let pd = self.r.pd as usize;
        if pd < PARAMS {
            v[pd]
        } else {
            v[0]
        }
    }

    fn v_fix(&self) -> u64 {
        let r = &self.r;
        let v24 = (self.sel(&r.centre) + (r.off & m(24))) & m(24);
        if r.pd == 3 && ((v24 >> 23) & 1 == 1 || v24 == 0) {
            1
        } else {
            v24
        }
    }

    /// Output ports (after the last edge).
    pub fn outputs(&self) -> SeqOutputs {
        let r = &self.r;
        let mut params = [0u64; 3];
        for (d, &b) in r.best.iter().enumerate() {
            let at = 24 * d;
            params[at / 64] |= b << (at % 64);
            if at % 64 > 40 {
                params[at / 64 + 1] |= b >> (64 - at % 64);
            }
        }
        let port = self.pram_port();
        SeqOutputs {
            start: r.start_r,
            pose: r.pose_r,
            running: r.run_r,
            finished: r.fin_r,
            iterations: r.iter_done as u16,
            best_cost: r.best_cost_r,
            best_max: r.best_max_r,
            params,
            p_we: port.we,
            p_waddr: port.addr as u16,
            p_wdata: port.data as u32,
            mul_product: r.m_acc,
        }
    }

    /// One rising clock edge; `i` are the input ports before it.
    pub fn step(&mut self, i: &SeqInputs) {
        let r = self.r;
        let mut n = r;
        let (cfg_addr, cfg_data) = ((i.cfg_addr as u64) & m(5), i.cfg_data & m(48));
        let cost_in = i.cost & m(48);

        // ---- Combinational signals (in the kernel's order).
        let s = Signals::of(self, i);

        // ---- Memory ports and datapath controls: defaults.
        let pram_w = self.pram_port();
        let pram_ra = r.pa as usize;
        let cram_ra = r.cra as usize;
        let wram_w = WritePort {
            we: r.state == SeqState::WRun && (r.sq >> 2) & 1 == 1,
            addr: (r.cnt & m(8)) as usize,
            data: s.exp_data as u16,
        };
        let wram_ra = r.wra as usize;
        let mut d = Drive {
            cram_w: WritePort {
                we: false,
                addr: (r.i & m(8)) as usize,
                data: r.costr as u128 | (r.maxd as u128) << 48,
            },
            rf_ra: r.op_b as usize,
            rf_w: WritePort { we: false, addr: r.op_dst as usize, data: sx(s.cor_v, 20) as u64 & m(26) },
            mul_go: false,
            mul_a_in: s.sel_sigma & m(26),
            mul_b_in: sx(s.u_hi, 16) as u64 & m(18),
            div_go: false,
        };
        n.start_r = false;
        let div_n_in = s.acc_abs;

        // The pipeline's results, taken in any state (the kernel's order).
        n.maxd = s.maxd_next;
        if i.cost_valid {
            n.costr = cost_in;
            n.inflight = false;
        }

        // ---- Configuration writes.
        if i.cfg_we {
            let a = cfg_addr as usize;
            if a < 7 {
                n.centre[a] = cfg_data & m(24);
            } else if a < 14 {
                n.cap[a - 7] = cfg_data & m(22);
            } else if a < 21 {
                n.floor[a - 14] = cfg_data & m(22);
            }
            match a {
                21 => n.seed = cfg_data & m(32),
                22 => n.thr_cost = cfg_data,
                23 => n.thr_max = cfg_data & m(34),
                24 => {
                    n.n_part = cfg_data & m(9);
                    n.n_iter = (cfg_data >> 16) & m(16);
                    n.tq = (cfg_data >> 32) & m(6);
                }
                _ => {}
            }
        }

        // ---- The state's arm.
        states::next(&r, &s, i, &mut n, &mut d);
        let Drive { cram_w, rf_ra, rf_w, mut mul_go, mut mul_a_in, mut mul_b_in, div_go } = d;

        // ---- The pipelined multiplier: operands, the carry-save product (`m_p`, the sum
        // of the RTL's two rows), the product; `m_v` marks which stages hold a started one.
        // Lent out while no run is in progress.
        if !r.run_r {
            (mul_go, mul_a_in, mul_b_in) = (i.ext_go, i.ext_a & m(26), i.ext_b & m(18));
        }
        if mul_go {
            n.m_a = sx(mul_a_in & m(26), 26) as u64 & m(44);
            n.m_b = mul_b_in & m(18);
            n.m_cnt = 2;
        } else if r.m_cnt != 0 {
            n.m_cnt = r.m_cnt - 1;
        }
        n.m_p = (sx(r.m_a, 44).wrapping_mul(sx(r.m_b, 18)) as u64) & m(44);
        n.m_acc = r.m_p;
        n.m_v = ((r.m_v << 1) | mul_go as u64) & m(3);
        // ---- The serial divider: 24 steps, the dividend's top half already in the
        // remainder (every quotient is below 2^24).
        let rem2 = ((r.dv_rem << 1) | ((r.dv_n >> 47) & 1)) & m(25);
        if div_go {
            n.dv_n = (div_n_in << 24) & m(48);
            n.dv_d = r.w_sum;
            n.dv_rem = (div_n_in >> 24) & m(24);
            n.dv_cnt = 24;
        } else if r.dv_cnt != 0 {
            if rem2 >= r.dv_d {
                n.dv_rem = (rem2 - r.dv_d) & m(25);
                n.dv_n = ((r.dv_n << 1) | 1) & m(48);
            } else {
                n.dv_rem = rem2;
                n.dv_n = (r.dv_n << 1) & m(48);
            }
            n.dv_cnt = r.dv_cnt - 1;
        }

        if i.reset {
            n.state = SeqState::Idle;
            n.run_r = false;
            n.fin_r = false;
            n.m_cnt = 0;
            n.m_v = 0;
            n.dv_cnt = 0;
        }

        // ---- The memories: read first (the old contents), then write.
        n.pram_q = self.pram[pram_ra] as u64;
        n.cram_q = self.cram[cram_ra];
        n.wram_q = self.wram[wram_ra] as u64;
        n.rf_q = self.rf[rf_ra];
        if pram_w.we {
            self.pram[pram_w.addr] = (pram_w.data & m(24)) as u32;
        }
        if cram_w.we {
            self.cram[cram_w.addr] = cram_w.data & ((1u128 << 82) - 1);
        }
        if wram_w.we {
            self.wram[wram_w.addr] = wram_w.data;
        }
        if rf_w.we {
            self.rf[rf_w.addr] = rf_w.data & m(26);
        }
        self.r = n;
    }
}
