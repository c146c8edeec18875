//! The model's registers (every `DFF` of the RTL and the RAMs' registered read data) and
//! the bit helpers its next-state logic uses.

use crate::filter::pf::PARAMS;
use crate::filter::seq_state::SeqState;

/// `2^bits - 1`.
pub(super) const fn m(bits: u32) -> u64 {
    if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    }
}

/// Sign-extend the low `bits` of `v`.
pub(super) fn sx(v: u64, bits: u32) -> i64 {
    ((v << (64 - bits)) as i64) >> (64 - bits)
}

/// The registers (every `DFF` of the RTL, and the RAMs' registered read data).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Regs {
    pub(super) centre: [u64; PARAMS],
    pub(super) cap: [u64; PARAMS],
    pub(super) floor: [u64; PARAMS],
    pub(super) sigma: [u64; PARAMS],
    pub(super) est: [u64; PARAMS],
    pub(super) best: [u64; PARAMS],
    pub(super) cur: [u64; PARAMS],
    pub(super) n_part: u64,
    pub(super) n_iter: u64,
    pub(super) tq: u64,
    pub(super) seed: u64,
    pub(super) thr_cost: u64,
    pub(super) thr_max: u64,
    pub(super) state: SeqState,
    pub(super) ret: SeqState,
    pub(super) ret2: SeqState,
    pub(super) rng: u64,
    pub(super) k: u64,
    pub(super) iter_done: u64,
    pub(super) run_r: bool,
    pub(super) fin_r: bool,
    pub(super) first: bool,
    pub(super) half: bool,
    pub(super) i: u64,
    pub(super) ie: u64,
    pub(super) inflight: bool,
    pub(super) havep: bool,
    pub(super) j: u64,
    pub(super) pd: u64,
    pub(super) spread: bool,
    pub(super) pa: u64,
    pub(super) cra: u64,
    pub(super) wra: u64,
    pub(super) x_r: u64,
    pub(super) w_r: u64,
    pub(super) sq: u64,
    pub(super) off: u64,
    pub(super) start_r: bool,
    pub(super) pose_r: [u64; 4],
    pub(super) maxd: u64,
    pub(super) costr: u64,
    pub(super) cmin: u64,
    pub(super) imin: u64,
    pub(super) best_cost_r: u64,
    pub(super) best_max_r: u64,
    pub(super) p: u64,
    pub(super) lo: u64,
    pub(super) hi: u64,
    pub(super) mask: u64,
    pub(super) cnt: u64,
    pub(super) pre: u64,
    pub(super) sh: u64,
    pub(super) w_sum: u64,
    pub(super) acc: u64,
    pub(super) lft: u64,
    pub(super) rgt: u64,
    pub(super) m_a: u64,
    pub(super) m_b: u64,
    pub(super) m_p: u64,
    pub(super) m_acc: u64,
    pub(super) m_v: u64,
    pub(super) m_cnt: u64,
    pub(super) dv_n: u64,
    pub(super) dv_d: u64,
    pub(super) dv_rem: u64,
    pub(super) dv_cnt: u64,
    pub(super) cx: u64,
    pub(super) cy: u64,
    pub(super) cz: u64,
    pub(super) ci: u64,
    pub(super) cj: u64,
    pub(super) cflip: bool,
    pub(super) pc: u64,
    pub(super) op_kind: u64,
    pub(super) op_dst: u64,
    pub(super) op_b: u64,
    pub(super) opa: u64,
    // The RAMs' read data registers.
    pub(super) pram_q: u64,
    pub(super) cram_q: u128,
    pub(super) wram_q: u64,
    pub(super) rf_q: u64,
}

/// A RAM write port's signals.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct WritePort<T> {
    pub(super) we: bool,
    pub(super) addr: usize,
    pub(super) data: T,
}

/// `pose >> 18 | v << 198` on the 216-bit pose word.
pub(super) fn shift_in18(w: [u64; 4], v: u64) -> [u64; 4] {
    let mut o = [0u64; 4];
    for k in 0..4 {
        o[k] = w[k] >> 18;
        if k < 3 {
            o[k] |= w[k + 1] << 46;
        }
    }
    o[3] = (o[3] & m(6)) | ((v & m(18)) << 6);
    o
}
