//! [`SequencerModel`]: the RTL's registers, RAMs and next-state logic, clock for clock.

use super::{SeqInputs, SeqOutputs};
use crate::common::format::exp_table;
use crate::filter::pf::{Particle, CORDIC_ATAN, CORDIC_K, PARAMS, POSE_PROGRAM};

use crate::filter::seq_state::SeqState;

mod regs;

use regs::{m, shift_in18, sx, Regs, WritePort};

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
        let (cost_in, nn_dist) = (i.cost & m(48), i.nn_dist & m(34));

        // ---- Combinational signals (in the kernel's order).
        let sel_centre = self.sel(&r.centre);
        let sel_sigma = self.sel(&r.sigma);
        let sel_floor = self.sel(&r.floor);
        let sel_cap = self.sel(&r.cap);
        let sel_est = self.sel(&r.est);
        let rng_t1 = (r.rng ^ (r.rng << 13)) & m(32);
        let rng_t2 = rng_t1 ^ (rng_t1 >> 17);
        let rng_next = (rng_t2 ^ (rng_t2 << 5)) & m(32);
        let u_hi = (r.rng >> 16) & m(16);
        let prod_sh14 = (r.m_acc >> 14) & m(26);
        let prod_sh15 = (r.m_acc >> 15) & m(26);
        let ref24 = if r.spread { sel_est } else { sel_centre };
        let diff24 = r.x_r.wrapping_sub(ref24) & m(24);
        let diff26 = sx(diff24, 24) as u64 & m(26);
        let lim26 = (sel_sigma << 1) & m(26);
        let v_fix = self.v_fix();
        let ex_now = ((r.cram_q as u64) & m(48)).wrapping_sub(r.cmin) & m(48);
        let ex_masked = ex_now & !r.mask & m(48);
        let ang = match r.cj {
            1 => r.cur[5],
            2 => r.cur[6],
            _ => r.cur[4],
        };
        let ang_x = ang ^ 0x80_0000;
        let sel_atan = self.atan[r.ci as usize];
        let ones22 = m(22);
        let ashr22 = |v: u64, s: u64| -> u64 {
            let l = if s >= 64 { 0 } else { v >> s };
            if (v >> 21) & 1 == 1 {
                (l | !(if s >= 64 { 0 } else { ones22 >> s })) & m(22)
            } else {
                l
            }
        };
        let cx_sh = ashr22(r.cx, r.ci);
        let cy_sh = ashr22(r.cy, r.ci);
        let cor_out = if r.state == SeqState::CorSin { r.cy } else { r.cx };
        let cor_sum = (cor_out + 2) & m(22);
        let cor_r = (cor_sum >> 2) & m(20);
        let cor_v = if r.cflip { 0u64.wrapping_sub(cor_r) & m(20) } else { cor_r };
        let prog_word = self.prog[r.pc as usize];
        let rf_b = r.rf_q;
        let m_round16 = (r.m_acc + 0x8000) & m(44);
        let m_round22 = (r.m_acc + 0x20_0000) & m(44);
        let m_t22 = (m_round22 >> 22) & m(22);
        let mut m_sat = m_t22 & m(18);
        if (m_t22 ^ 0x20_0000) > 0x21_ffff {
            m_sat = 0x1_ffff;
        }
        if (m_t22 ^ 0x20_0000) < 0x1e_0000 {
            m_sat = 0x2_0000;
        }
        let tr_in = match r.cj {
            1 => r.cur[1],
            2 => r.cur[2],
            _ => r.cur[0],
        };
        let tr_y = (sx(tr_in, 24) + 32) as u64 & m(25);
        let tr_t = (tr_y >> 6) & m(19);
        let mut tr_sat = tr_t & m(18);
        if (tr_t ^ 0x4_0000) > 0x5_ffff {
            tr_sat = 0x1_ffff;
        }
        if (tr_t ^ 0x4_0000) < 0x2_0000 {
            tr_sat = 0x2_0000;
        }
        let acc_neg = (r.acc >> 47) & 1 == 1;
        let acc_abs = if acc_neg { 0u64.wrapping_sub(r.acc) & m(48) } else { r.acc };
        let q26 = r.dv_n & m(26);
        let mean26 = if acc_neg { 0u64.wrapping_sub(q26) & m(26) } else { q26 };
        let dev26 = (q26 + (q26 >> 2)) & m(26);
        let mut sig_new = dev26 & m(22);
        if dev26 > sel_cap {
            sig_new = sel_cap;
        }
        if dev26 < sel_floor {
            sig_new = sel_floor;
        }
        let est_v = (sel_centre + (mean26 & m(24))) & m(24);
        let est_fix = if r.pd == 3 && ((est_v >> 23) & 1 == 1 || est_v == 0) { 1 } else { est_v };
        let abs26 = if (diff26 >> 25) & 1 == 1 { 0u64.wrapping_sub(diff26) & m(26) } else { diff26 };
        let maxd_next = if i.nn_valid && nn_dist > r.maxd { nn_dist } else { r.maxd };
        let t_entry = if r.sh > 255 { 255 } else { r.sh & m(8) };
        let exp_data = self.exp[t_entry as usize] as u64;
        let mut e_tmp = r.tq;
        if r.p > 2 && r.p - 2 > r.tq {
            e_tmp = r.p - 2;
        }

        // ---- Memory ports and datapath controls: defaults.
        let pram_w = self.pram_port();
        let pram_ra = r.pa as usize;
        let mut cram_w =
            WritePort { we: false, addr: (r.i & m(8)) as usize, data: r.costr as u128 | (r.maxd as u128) << 48 };
        let cram_ra = r.cra as usize;
        let wram_w = WritePort {
            we: r.state == SeqState::WRun && (r.sq >> 2) & 1 == 1,
            addr: (r.cnt & m(8)) as usize,
            data: exp_data as u16,
        };
        let wram_ra = r.wra as usize;
        let mut rf_ra = r.op_b as usize;
        let mut rf_w = WritePort { we: false, addr: r.op_dst as usize, data: sx(cor_v, 20) as u64 & m(26) };
        n.start_r = false;
        let mut mul_go = false;
        let mut mul_a_in = sel_sigma & m(26);
        let mut mul_b_in = sx(u_hi, 16) as u64 & m(18);
        let mut div_go = false;
        let div_n_in = acc_abs;

        // The pipeline's results, taken in any state (the kernel's order).
        n.maxd = maxd_next;
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

        // `(x + 1) == n_part` / `< n_part` are 32-bit in the Verilog: no wrap at 9 bits.
        let last = |x: u64| x + 1 == r.n_part;
        let pa_of = |half: bool, p: u64| ((half as u64) << 11) | ((p & m(8)) << 3);

        use SeqState as S;
        match r.state {
            S::Idle => {
                if i.go {
                    for q in 0..PARAMS {
                        n.sigma[q] = r.cap[q];
                        if r.floor[q] > r.cap[q] {
                            n.cap[q] = r.floor[q];
                            n.sigma[q] = r.floor[q];
                        }
                        n.cur[q] = r.centre[q];
                    }
                    n.rng = if r.seed == 0 { 1 } else { r.seed };
                    n.run_r = true;
                    n.fin_r = false;
                    n.inflight = false;
                    n.havep = false;
                    // Nothing evaluated yet: Status reports no best cost (not the last run's).
                    n.best_cost_r = m(48);
                    n.iter_done = 0;
                    n.k = 0;
                    n.half = false;
                    n.cj = 0;
                    n.ret = S::EvStart;
                    n.ret2 = S::StartDone;
                    n.state = S::CorInit;
                }
            }
            // ---- Pose subroutine.
            S::CorInit => {
                n.cx = CORDIC_K as u64;
                n.cy = 0;
                n.ci = 0;
                n.cflip = false;
                n.cz = sx(ang, 24) as u64 & m(25);
                // `ang_x > 0xc0_0000 || ang_x < 0x40_0000`.
                if !(0x40_0000..=0xc0_0000).contains(&ang_x) {
                    n.cflip = true;
                    n.cz = sx(ang_x, 24) as u64 & m(25);
                }
                n.state = S::CorStep;
            }
            S::CorStep => {
                if (r.cz >> 24) & 1 == 0 {
                    n.cx = r.cx.wrapping_sub(cy_sh) & m(22);
                    n.cy = (r.cy + cx_sh) & m(22);
                    n.cz = r.cz.wrapping_sub(sel_atan) & m(25);
                } else {
                    n.cx = (r.cx + cy_sh) & m(22);
                    n.cy = r.cy.wrapping_sub(cx_sh) & m(22);
                    n.cz = (r.cz + sel_atan) & m(25);
                }
                n.ci = (r.ci + 1) & m(5);
                if r.ci == 17 {
                    n.state = S::CorCos;
                }
            }
            S::CorCos => {
                rf_w.we = true;
                rf_w.addr = ((r.cj << 1) & m(5)) as usize;
                n.state = S::CorSin;
            }
            S::CorSin => {
                rf_w.we = true;
                rf_w.addr = (((r.cj << 1) + 1) & m(5)) as usize;
                n.cj = (r.cj + 1) & m(2);
                n.state = if r.cj == 2 { S::PoseScale } else { S::CorInit };
            }
            S::PoseScale => {
                rf_w.we = true;
                rf_w.addr = 6;
                rf_w.data = sx(r.cur[3], 24) as u64 & m(26);
                n.pc = 0;
                n.cj = 0;
                n.state = S::OpFetch;
            }
            S::OpFetch => {
                rf_ra = ((prog_word >> 7) & m(5)) as usize;
                n.op_kind = prog_word & m(2);
                n.op_dst = (prog_word >> 2) & m(5);
                n.op_b = (prog_word >> 12) & m(5);
                n.state = S::OpA;
            }
            S::OpA => {
                n.opa = r.rf_q;
                n.state = S::OpB;
            }
            S::OpB => {
                if (r.op_kind >> 1) & 1 == 1 {
                    rf_w.we = true;
                    rf_w.data =
                        if r.op_kind & 1 == 1 { r.opa.wrapping_sub(rf_b) & m(26) } else { (r.opa + rf_b) & m(26) };
                    n.pc = (r.pc + 1) & m(5);
                    n.state = S::OpFetch;
                } else {
                    mul_go = true;
                    mul_a_in = r.opa;
                    mul_b_in = rf_b & m(18);
                    n.state = S::OpMul;
                }
            }
            S::OpMul => {
                if r.m_cnt == 0 {
                    if r.op_kind & 1 == 1 {
                        n.pose_r = shift_in18(r.pose_r, m_sat);
                    } else {
                        rf_w.we = true;
                        rf_w.data = (m_round16 >> 16) & m(26);
                    }
                    n.pc = (r.pc + 1) & m(5);
                    n.state = if r.pc == 27 { S::PoseT } else { S::OpFetch };
                }
            }
            S::PoseT => {
                n.pose_r = shift_in18(r.pose_r, tr_sat);
                n.cj = (r.cj + 1) & m(2);
                if r.cj == 2 {
                    n.state = r.ret;
                }
            }
            // ---- Evaluate subroutine.
            S::EvStart => {
                if i.nn_ready {
                    n.start_r = true;
                    n.maxd = 0;
                    n.state = S::EvWait;
                }
            }
            S::EvWait => {
                if i.cost_valid {
                    n.state = r.ret2;
                }
            }
            S::StartDone => {
                n.best_cost_r = r.costr;
                n.best_max_r = r.maxd;
                n.best = r.cur;
                n.state = S::IterBegin;
            }
            // ---- One iteration.
            S::IterBegin => {
                n.i = 0;
                n.pd = 0;
                n.cmin = m(48);
                n.imin = 0;
                n.first = r.k == 0;
                n.pa = (r.half as u64) << 11;
                n.state = S::PropAddr;
            }
            S::PropAddr => {
                n.rng = rng_next;
                n.state = S::PropRead;
            }
            S::PropRead => {
                mul_go = true;
                n.state = S::PropMul;
            }
            S::PropMul => {
                n.x_r = r.pram_q;
                if r.m_cnt == 0 {
                    n.off = if r.first { prod_sh14 } else { (diff26 + prod_sh15) & m(26) };
                    n.state = S::PropClamp;
                }
            }
            S::PropClamp => {
                let neg_lim = 0u64.wrapping_sub(lim26) & m(26);
                if (r.off ^ 0x200_0000) > (lim26 ^ 0x200_0000) {
                    n.off = lim26;
                }
                if (r.off ^ 0x200_0000) < (neg_lim ^ 0x200_0000) {
                    n.off = neg_lim;
                }
                n.state = S::PropWrite;
            }
            S::PropWrite => {
                // (The write port is `pram_port`.)
                if (r.pd as usize) < PARAMS {
                    n.cur[r.pd as usize] = v_fix;
                }
                n.pa = (r.pa + 1) & m(12);
                n.pd = (r.pd + 1) & m(3);
                if r.pd == 6 {
                    n.pd = 0;
                    n.pa = (r.pa + 2) & m(12);
                    n.cj = 0;
                    n.ret = S::EvSync;
                    n.state = S::CorInit;
                } else {
                    n.state = S::PropAddr;
                }
            }
            S::EvSync => {
                if !r.inflight {
                    if r.havep {
                        n.state = S::PartStore;
                    } else if r.i == r.n_part {
                        // The temperature's binary search over p in 0..=48, from the middle.
                        n.lo = 0;
                        n.hi = 48;
                        n.p = 24;
                        n.mask = m(24);
                        n.state = S::TPass;
                    } else {
                        n.state = S::EvLaunch;
                    }
                }
            }
            S::EvLaunch => {
                if i.nn_ready {
                    n.start_r = true;
                    n.maxd = 0;
                    n.inflight = true;
                    n.havep = true;
                    n.ie = r.i;
                    n.i = (r.i + 1) & m(9);
                    n.state = if last(r.i) { S::EvSync } else { S::PropAddr };
                }
            }
            S::PartStore => {
                cram_w.we = true;
                cram_w.addr = (r.ie & m(8)) as usize;
                if r.costr < r.cmin {
                    n.cmin = r.costr;
                    n.imin = r.ie & m(8);
                }
                n.havep = false;
                n.state = S::EvSync;
            }
            // ---- Temperature.
            S::TPass => {
                n.i = 0;
                n.cnt = 0;
                n.sq = 0;
                n.state = S::TRun;
            }
            S::TRun => {
                // Address cost `i` while there is one; count the cost read two clocks ago.
                let issue = r.i != r.n_part;
                if issue {
                    n.cra = r.i & m(8);
                    n.i = (r.i + 1) & m(9);
                }
                n.sq = ((r.sq << 1) | issue as u64) & m(2);
                if (r.sq >> 1) & 1 == 1 && ex_masked == 0 {
                    n.cnt = (r.cnt + 1) & m(9);
                }
                if !issue && r.sq & 1 == 0 {
                    n.state = S::TCheck;
                }
            }
            S::TCheck => {
                // More than half the excesses below 2^p: the bit length is at most p.
                if r.cnt > (r.n_part >> 1) {
                    n.hi = r.p;
                } else {
                    n.lo = (r.p + 1) & m(6);
                }
                n.state = S::TMid;
            }
            S::TMid => {
                let mid = ((r.lo + r.hi) >> 1) & m(6);
                if r.lo == r.hi {
                    n.p = r.lo;
                    n.state = S::TSet;
                } else {
                    n.p = mid;
                    n.mask = !(m(48) << mid) & m(48);
                    n.state = S::TPass;
                }
            }
            S::TSet => {
                n.pre = if e_tmp > 5 { (e_tmp - 5) & m(6) } else { 0 };
                n.i = 0;
                n.cnt = 0;
                n.sq = 0;
                n.w_sum = 0;
                n.state = S::WRun;
            }
            // ---- Weights.
            S::WRun => {
                // Address cost `i` while there is one; shift the excess read two clocks ago;
                // store and sum the weight of the one before (`cnt`, in `wram_w`).
                let issue = r.i != r.n_part;
                if issue {
                    n.cra = r.i & m(8);
                    n.i = (r.i + 1) & m(9);
                }
                n.sq = ((r.sq << 1) | issue as u64) & m(3);
                if (r.sq >> 1) & 1 == 1 {
                    n.sh = if r.pre >= 64 { 0 } else { ex_now >> r.pre };
                }
                if (r.sq >> 2) & 1 == 1 {
                    n.w_sum = (r.w_sum + exp_data) & m(24);
                    n.cnt = (r.cnt + 1) & m(9);
                }
                if !issue && r.sq & 3 == 0 {
                    n.state = S::BestCheck;
                }
            }
            // ---- The best particle.
            S::BestCheck => {
                n.cra = r.imin;
                n.pd = 0;
                if r.cmin < r.best_cost_r {
                    n.state = S::BestRec;
                } else {
                    n.spread = false;
                    n.state = S::SumBegin;
                }
            }
            S::BestRec => {
                n.pa = pa_of(r.half, r.imin);
                n.state = S::BestAddr;
            }
            S::BestAddr => {
                n.best_cost_r = (r.cram_q as u64) & m(48);
                n.best_max_r = ((r.cram_q >> 48) as u64) & m(34);
                n.pa = (r.pa + 1) & m(12);
                n.state = S::BestData;
            }
            S::BestData => {
                if (r.pd as usize) < PARAMS {
                    n.best[r.pd as usize] = r.pram_q;
                }
                n.pa = (r.pa + 1) & m(12);
                n.pd = (r.pd + 1) & m(3);
                if r.pd == 6 {
                    n.pd = 0;
                    n.spread = false;
                    n.state = S::SumBegin;
                }
            }
            // ---- Estimate and spread.
            S::SumBegin => {
                n.acc = 0;
                n.i = 0;
                n.sq = 0;
                n.state = S::SumRun;
            }
            S::SumRun => {
                // Address particle `i` while there is one; take the parameter and weight read
                // two clocks ago; multiply the ones taken a clock ago; add the product that
                // comes out of the multiplier.
                let issue = r.i != r.n_part;
                if issue {
                    n.pa = pa_of(r.half, r.i) | r.pd;
                    n.wra = r.i & m(8);
                    n.i = (r.i + 1) & m(9);
                }
                n.sq = ((r.sq << 1) | issue as u64) & m(3);
                n.x_r = r.pram_q;
                n.w_r = r.wram_q;
                if (r.sq >> 2) & 1 == 1 {
                    mul_go = true;
                    mul_b_in = r.w_r & m(18);
                    mul_a_in = if r.spread { abs26 } else { diff26 };
                }
                if (r.m_v >> 2) & 1 == 1 {
                    let prod48 = (sx(r.m_acc, 44) as u64) & m(48);
                    n.acc = (r.acc + prod48) & m(48);
                }
                if !issue && r.sq == 0 && r.m_cnt == 0 {
                    n.state = S::SumDivGo;
                }
            }
            S::SumDivGo => {
                div_go = true;
                n.state = S::SumDivWait;
            }
            S::SumDivWait => {
                if r.dv_cnt == 0 {
                    if (r.pd as usize) < PARAMS {
                        if r.spread {
                            n.sigma[r.pd as usize] = sig_new;
                        } else {
                            n.est[r.pd as usize] = est_fix;
                        }
                    }
                    n.pd = (r.pd + 1) & m(3);
                    n.state = S::SumBegin;
                    if r.pd == 6 {
                        n.pd = 0;
                        if r.spread {
                            n.state = S::EstEval;
                        } else {
                            n.spread = true;
                        }
                    }
                }
            }
            S::EstEval => {
                n.spread = false;
                n.cur = r.est;
                n.cj = 0;
                n.ret = S::EvStart;
                n.ret2 = S::EstDone;
                n.state = S::CorInit;
            }
            S::EstDone => {
                if r.costr < r.best_cost_r {
                    n.best_cost_r = r.costr;
                    n.best_max_r = r.maxd;
                    n.best = r.est;
                }
                n.state = S::Centre;
            }
            S::Centre => {
                n.centre = r.best;
                n.iter_done = (r.k + 1) & m(16);
                n.state = S::StopCheck;
            }
            S::StopCheck => {
                if (r.best_cost_r <= r.thr_cost && r.best_max_r <= r.thr_max) || r.iter_done == r.n_iter {
                    n.state = S::Fin;
                } else {
                    n.rng = rng_next;
                    n.state = S::RsBegin;
                }
            }
            // ---- Systematic resampling.
            S::RsBegin => {
                mul_go = true;
                mul_a_in = r.w_sum;
                mul_b_in = u_hi;
                n.wra = 0;
                n.i = 0;
                n.j = 0;
                n.rgt = 0;
                n.state = S::RsL;
            }
            S::RsL => {
                if r.m_cnt == 0 {
                    n.lft = r.m_acc;
                    n.state = S::RsWData;
                }
            }
            S::RsWAddr => {
                n.wra = r.i & m(8);
                n.state = S::RsWWait;
            }
            S::RsWWait => n.state = S::RsWData,
            S::RsWData => {
                mul_go = true;
                mul_a_in = r.n_part;
                mul_b_in = r.wram_q;
                n.state = S::RsWMul;
            }
            S::RsWMul => {
                if r.m_cnt == 0 {
                    n.rgt = (r.rgt + (r.m_acc << 16)) & m(50);
                    n.state = S::RsLoop;
                }
            }
            S::RsLoop => {
                if r.lft > r.rgt && r.i + 1 < r.n_part {
                    n.i = (r.i + 1) & m(9);
                    n.state = S::RsWAddr;
                } else {
                    n.pd = 0;
                    n.pa = pa_of(r.half, r.i);
                    n.state = S::CpWait;
                }
            }
            S::CpWait => {
                n.pa = (r.pa + 1) & m(12);
                n.state = S::CpData;
            }
            S::CpData => {
                // (The write port is `pram_port`.)
                n.pa = (r.pa + 1) & m(12);
                n.pd = (r.pd + 1) & m(3);
                n.state = if r.pd == 6 { S::CpNext } else { S::CpData };
            }
            S::CpNext => {
                n.lft = (r.lft + (r.w_sum << 16)) & m(50);
                n.j = (r.j + 1) & m(9);
                n.state = if last(r.j) { S::RsDone } else { S::RsLoop };
            }
            S::RsDone => {
                n.half = !r.half;
                n.k = (r.k + 1) & m(16);
                n.state = S::IterBegin;
            }
            S::Fin => {
                n.cur = r.best;
                n.cj = 0;
                n.ret = S::FinDone;
                n.state = S::CorInit;
            }
            S::FinDone => {
                n.run_r = false;
                n.fin_r = true;
                n.state = S::Idle;
            }
        }

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
            n.state = S::Idle;
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
