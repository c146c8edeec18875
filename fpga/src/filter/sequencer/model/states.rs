//! The sequencer model's next-state logic: the kernel's one `match` over [`SeqState`], an
//! arm a state, from the registers before the edge (`r`) into the registers after it (`n`)
//! and the memory ports and datapath starts the state drives ([`Drive`]).

use super::regs::{m, shift_in18, sx, Regs, WritePort};
use super::signals::Signals;
use crate::filter::pf::{CORDIC_K, PARAMS};
use crate::filter::seq_state::SeqState;
use crate::filter::sequencer::SeqInputs;

/// What a state drives besides the registers: the memories' ports and the starts of the
/// multiplier and the divider (their defaults set by the step before the state's arm).
#[derive(Clone, Copy, Debug)]
pub(super) struct Drive {
    pub(super) cram_w: WritePort<u128>,
    pub(super) rf_ra: usize,
    pub(super) rf_w: WritePort<u64>,
    pub(super) mul_go: bool,
    pub(super) mul_a_in: u64,
    pub(super) mul_b_in: u64,
    pub(super) div_go: bool,
}

/// The state's arm: `n` (the registers after the edge, as the step has set them so far)
/// and `d` from the registers `r`, the signals `s` and the input ports `i`.
pub(super) fn next(r: &Regs, s: &Signals, i: &SeqInputs, n: &mut Regs, d: &mut Drive) {
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
            n.cz = sx(s.ang, 24) as u64 & m(25);
            // `ang_x > 0xc0_0000 || ang_x < 0x40_0000`.
            if !(0x40_0000..=0xc0_0000).contains(&s.ang_x) {
                n.cflip = true;
                n.cz = sx(s.ang_x, 24) as u64 & m(25);
            }
            n.state = S::CorStep;
        }
        S::CorStep => {
            if (r.cz >> 24) & 1 == 0 {
                n.cx = r.cx.wrapping_sub(s.cy_sh) & m(22);
                n.cy = (r.cy + s.cx_sh) & m(22);
                n.cz = r.cz.wrapping_sub(s.sel_atan) & m(25);
            } else {
                n.cx = (r.cx + s.cy_sh) & m(22);
                n.cy = r.cy.wrapping_sub(s.cx_sh) & m(22);
                n.cz = (r.cz + s.sel_atan) & m(25);
            }
            n.ci = (r.ci + 1) & m(5);
            if r.ci == 17 {
                n.state = S::CorCos;
            }
        }
        S::CorCos => {
            d.rf_w.we = true;
            d.rf_w.addr = ((r.cj << 1) & m(5)) as usize;
            n.state = S::CorSin;
        }
        S::CorSin => {
            d.rf_w.we = true;
            d.rf_w.addr = (((r.cj << 1) + 1) & m(5)) as usize;
            n.cj = (r.cj + 1) & m(2);
            n.state = if r.cj == 2 { S::PoseScale } else { S::CorInit };
        }
        S::PoseScale => {
            d.rf_w.we = true;
            d.rf_w.addr = 6;
            d.rf_w.data = sx(r.cur[3], 24) as u64 & m(26);
            n.pc = 0;
            n.cj = 0;
            n.state = S::OpFetch;
        }
        S::OpFetch => {
            d.rf_ra = ((s.prog_word >> 7) & m(5)) as usize;
            n.op_kind = s.prog_word & m(2);
            n.op_dst = (s.prog_word >> 2) & m(5);
            n.op_b = (s.prog_word >> 12) & m(5);
            n.state = S::OpA;
        }
        S::OpA => {
            n.opa = r.rf_q;
            n.state = S::OpB;
        }
        S::OpB => {
            if (r.op_kind >> 1) & 1 == 1 {
                d.rf_w.we = true;
                d.rf_w.data =
                    if r.op_kind & 1 == 1 { r.opa.wrapping_sub(s.rf_b) & m(26) } else { (r.opa + s.rf_b) & m(26) };
                n.pc = (r.pc + 1) & m(5);
                n.state = S::OpFetch;
            } else {
                d.mul_go = true;
                d.mul_a_in = r.opa;
                d.mul_b_in = s.rf_b & m(18);
                n.state = S::OpMul;
            }
        }
        S::OpMul => {
            if r.m_cnt == 0 {
                if r.op_kind & 1 == 1 {
                    n.pose_r = shift_in18(r.pose_r, s.m_sat);
                } else {
                    d.rf_w.we = true;
                    d.rf_w.data = (s.m_round16 >> 16) & m(26);
                }
                n.pc = (r.pc + 1) & m(5);
                n.state = if r.pc == 27 { S::PoseT } else { S::OpFetch };
            }
        }
        S::PoseT => {
            n.pose_r = shift_in18(r.pose_r, s.tr_sat);
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
            n.rng = s.rng_next;
            n.state = S::PropRead;
        }
        S::PropRead => {
            d.mul_go = true;
            n.state = S::PropMul;
        }
        S::PropMul => {
            n.x_r = r.pram_q;
            if r.m_cnt == 0 {
                n.off = if r.first { s.prod_sh14 } else { (s.diff26 + s.prod_sh15) & m(26) };
                n.state = S::PropClamp;
            }
        }
        S::PropClamp => {
            let neg_lim = 0u64.wrapping_sub(s.lim26) & m(26);
            if (r.off ^ 0x200_0000) > (s.lim26 ^ 0x200_0000) {
                n.off = s.lim26;
            }
            if (r.off ^ 0x200_0000) < (neg_lim ^ 0x200_0000) {
                n.off = neg_lim;
            }
            n.state = S::PropWrite;
        }
        S::PropWrite => {
            // (The write port is `pram_port`.)
            if (r.pd as usize) < PARAMS {
                n.cur[r.pd as usize] = s.v_fix;
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
            d.cram_w.we = true;
            d.cram_w.addr = (r.ie & m(8)) as usize;
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
            if (r.sq >> 1) & 1 == 1 && s.ex_masked == 0 {
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
            n.pre = if s.e_tmp > 5 { (s.e_tmp - 5) & m(6) } else { 0 };
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
                n.sh = if r.pre >= 64 { 0 } else { s.ex_now >> r.pre };
            }
            if (r.sq >> 2) & 1 == 1 {
                n.w_sum = (r.w_sum + s.exp_data) & m(24);
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
                d.mul_go = true;
                d.mul_b_in = r.w_r & m(18);
                d.mul_a_in = if r.spread { s.abs26 } else { s.diff26 };
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
            d.div_go = true;
            n.state = S::SumDivWait;
        }
        S::SumDivWait => {
            if r.dv_cnt == 0 {
                if (r.pd as usize) < PARAMS {
                    if r.spread {
                        n.sigma[r.pd as usize] = s.sig_new;
                    } else {
                        n.est[r.pd as usize] = s.est_fix;
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
                n.rng = s.rng_next;
                n.state = S::RsBegin;
            }
        }
        // ---- Systematic resampling.
        S::RsBegin => {
            d.mul_go = true;
            d.mul_a_in = r.w_sum;
            d.mul_b_in = s.u_hi;
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
            d.mul_go = true;
            d.mul_a_in = r.n_part;
            d.mul_b_in = r.wram_q;
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
}
