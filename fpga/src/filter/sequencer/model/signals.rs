//! The sequencer model's combinational signals: what the kernel computes from the
//! registers (and the pipeline's result ports) before the state's arm uses it, in the
//! kernel's order.

use super::regs::{m, sx};
use super::SequencerModel;
use crate::filter::seq_state::SeqState;
use crate::filter::sequencer::SeqInputs;

/// The signals one edge's next-state logic reads (the ones the model only needs on the way
/// to these stay local to [`Signals::of`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Signals {
    pub(super) sel_sigma: u64,
    pub(super) rng_next: u64,
    pub(super) u_hi: u64,
    pub(super) prod_sh14: u64,
    pub(super) prod_sh15: u64,
    pub(super) diff26: u64,
    pub(super) lim26: u64,
    pub(super) v_fix: u64,
    pub(super) ex_now: u64,
    pub(super) ex_masked: u64,
    pub(super) ang: u64,
    pub(super) ang_x: u64,
    pub(super) sel_atan: u64,
    pub(super) cx_sh: u64,
    pub(super) cy_sh: u64,
    pub(super) cor_v: u64,
    pub(super) prog_word: u64,
    pub(super) rf_b: u64,
    pub(super) m_round16: u64,
    pub(super) m_sat: u64,
    pub(super) tr_sat: u64,
    pub(super) acc_abs: u64,
    pub(super) sig_new: u64,
    pub(super) est_fix: u64,
    pub(super) abs26: u64,
    pub(super) maxd_next: u64,
    pub(super) exp_data: u64,
    pub(super) e_tmp: u64,
}

impl Signals {
    /// The signals before the edge, from the registers, RAM read data and ROMs of `model`
    /// and the input ports `i`.
    pub(super) fn of(model: &SequencerModel, i: &SeqInputs) -> Signals {
        let r = &model.r;
        let nn_dist = i.nn_dist & m(34);
        let sel_centre = model.sel(&r.centre);
        let sel_sigma = model.sel(&r.sigma);
        let sel_floor = model.sel(&r.floor);
        let sel_cap = model.sel(&r.cap);
        let sel_est = model.sel(&r.est);
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
        let v_fix = model.v_fix();
        let ex_now = ((r.cram_q as u64) & m(48)).wrapping_sub(r.cmin) & m(48);
        let ex_masked = ex_now & !r.mask & m(48);
        let ang = match r.cj {
            1 => r.cur[5],
            2 => r.cur[6],
            _ => r.cur[4],
        };
        let ang_x = ang ^ 0x80_0000;
        let sel_atan = model.atan[r.ci as usize];
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
        let prog_word = model.prog[r.pc as usize];
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
        let exp_data = model.exp[t_entry as usize] as u64;
        let mut e_tmp = r.tq;
        if r.p > 2 && r.p - 2 > r.tq {
            e_tmp = r.p - 2;
        }

        Signals {
            sel_sigma,
            rng_next,
            u_hi,
            prod_sh14,
            prod_sh15,
            diff26,
            lim26,
            v_fix,
            ex_now,
            ex_masked,
            ang,
            ang_x,
            sel_atan,
            cx_sh,
            cy_sh,
            cor_v,
            prog_word,
            rf_b,
            m_round16,
            m_sat,
            tr_sat,
            acc_abs,
            sig_new,
            est_fix,
            abs26,
            maxd_next,
            exp_data,
            e_tmp,
        }
    }
}
