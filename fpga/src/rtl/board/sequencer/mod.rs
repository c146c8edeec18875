//! `PfSequencer`: the on-board particle filter (docs/sequencer.md), the RTL of
//! [`crate::pf::run`]. It owns the particle set (two halves of a 4,096 x 24 RAM), the
//! per-particle costs and weights and the state machine (`kernel.rs`), and drives the
//! nearest-neighbour pipeline through `start` / `pose`. Its arithmetic is one block a
//! file, each the twin of a [`crate::pf`] function (tests: `fpga/tests/sequencer_blocks.rs`):
//! - [`serial_mul`]: `SerialMul`, 26 x 18 bits in 18 clocks;
//! - [`serial_div`]: `SerialDiv`, 48 / 24 bits in 48 clocks ([`crate::pf::div_signed`]);
//! - [`xorshift`]: `Xorshift32`, the PRNG's step ([`crate::pf::Xorshift32`]);
//! - [`cordic`]: `Cordic`, cosine and sine in 18 steps ([`crate::pf::cordic`]);
//! - [`pose_program`]: `PoseProgram`, [`crate::pf::POSE_PROGRAM`] in ROM over a 32 x 26
//!   register file ([`crate::pf::run_program`]).
//!
//! Everything is sequential and small next to the pipeline's ~10^4 clocks per particle.
//! The cycle-accurate mirror is [`crate::sequencer::SequencerModel`].

use crate::format::exp_table;
use rust_hdl::prelude::*;

pub mod cordic;
mod kernel;
pub mod pose_program;
pub mod serial_div;
pub mod serial_mul;
pub mod xorshift;

pub use cordic::Cordic;
pub use pose_program::PoseProgram;
pub use serial_div::SerialDiv;
pub use serial_mul::SerialMul;
pub use xorshift::Xorshift32;

pub use crate::seq_state::SeqState;

/// The particle-filter sequencer.
#[derive(LogicBlock)]
pub struct PfSequencer {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (idle, no result).
    pub reset: Signal<In, Bit>,
    /// Write `cfg_data` to configuration word `cfg_addr` (0..7 centre, 7..14 sigma0,
    /// 14..21 floor, 21 seed, 22 thr_cost, 23 thr_max, 24 the header: particles in bits
    /// 0..16, iterations 16..32, temperature exponent 32..38).
    pub cfg_we: Signal<In, Bit>,
    /// Configuration word address.
    pub cfg_addr: Signal<In, Bits<5>>,
    /// Configuration word.
    pub cfg_data: Signal<In, Bits<48>>,
    /// Start a run (when idle).
    pub go: Signal<In, Bit>,
    /// The pipeline may be started.
    pub nn_ready: Signal<In, Bit>,
    /// The pipeline's cost is presented.
    pub cost_valid: Signal<In, Bit>,
    /// The cost.
    pub cost: Signal<In, Bits<48>>,
    /// A nearest-neighbour result is presented.
    pub nn_valid: Signal<In, Bit>,
    /// Its squared distance.
    pub nn_dist: Signal<In, Bits<34>>,
    /// Start the pipeline on `pose` (one clock).
    pub start: Signal<Out, Bit>,
    /// The pose (during a run: the particle's; after it: the best's).
    pub pose: Signal<Out, Bits<216>>,
    /// A run is in progress.
    pub running: Signal<Out, Bit>,
    /// A run has finished (until the next `go` or reset).
    pub finished: Signal<Out, Bit>,
    /// Iterations completed.
    pub iterations: Signal<Out, Bits<16>>,
    /// Best cost so far.
    pub best_cost: Signal<Out, Bits<48>>,
    /// Its largest squared distance.
    pub best_max: Signal<Out, Bits<34>>,
    /// The best parameters, 24 bits each, `[a, b, c, s, phi, theta, psi]` from bit 0.
    pub params: Signal<Out, Bits<168>>,
    /// Particle RAM write enable (observed by the co-simulation).
    pub p_we: Signal<Out, Bit>,
    /// Particle RAM write address `{half, particle, parameter}`.
    pub p_waddr: Signal<Out, Bits<12>>,
    /// Particle RAM write data.
    pub p_wdata: Signal<Out, Bits<24>>,
    // Configuration and filter state.
    centre: [DFF<Bits<24>>; 7],
    cap: [DFF<Bits<22>>; 7],
    floor: [DFF<Bits<22>>; 7],
    sigma: [DFF<Bits<22>>; 7],
    est: [DFF<Bits<24>>; 7],
    best: [DFF<Bits<24>>; 7],
    cur: [DFF<Bits<24>>; 7],
    n_part: DFF<Bits<9>>,
    n_iter: DFF<Bits<16>>,
    tq: DFF<Bits<6>>,
    seed: DFF<Bits<32>>,
    thr_cost: DFF<Bits<48>>,
    thr_max: DFF<Bits<34>>,
    state: DFF<SeqState>,
    ret: DFF<SeqState>,
    ret2: DFF<SeqState>,
    rng: DFF<Bits<32>>,
    k: DFF<Bits<16>>,
    iter_done: DFF<Bits<16>>,
    run_r: DFF<Bit>,
    fin_r: DFF<Bit>,
    first: DFF<Bit>,
    half: DFF<Bits<1>>,
    i: DFF<Bits<9>>,
    j: DFF<Bits<9>>,
    pd: DFF<Bits<3>>,
    spread: DFF<Bit>,
    pa: DFF<Bits<12>>,
    cra: DFF<Bits<8>>,
    wra: DFF<Bits<8>>,
    x_r: DFF<Bits<24>>,
    off: DFF<Bits<26>>,
    start_r: DFF<Bit>,
    pose_r: DFF<Bits<216>>,
    maxd: DFF<Bits<34>>,
    costr: DFF<Bits<48>>,
    cmin: DFF<Bits<48>>,
    imin: DFF<Bits<8>>,
    best_cost_r: DFF<Bits<48>>,
    best_max_r: DFF<Bits<34>>,
    p: DFF<Bits<6>>,
    mask: DFF<Bits<48>>,
    cnt: DFF<Bits<9>>,
    pre: DFF<Bits<6>>,
    sh: DFF<Bits<48>>,
    w_sum: DFF<Bits<24>>,
    acc: DFF<Bits<48>>,
    lft: DFF<Bits<50>>,
    rgt: DFF<Bits<50>>,
    cj: DFF<Bits<2>>,
    all48: Constant<Bits<48>>,
    sign44: Constant<Bits<44>>,
    sign48_44: Constant<Bits<48>>,
    // Memories.
    pram: RAM<Bits<24>, 12>,
    cram: RAM<Bits<82>, 8>,
    wram: RAM<Bits<16>, 8>,
    exp_rom: ROM<Bits<16>, 8>,
    // The arithmetic, one block each.
    mul: SerialMul,
    div: SerialDiv,
    xorshift: Xorshift32,
    cordic: Cordic,
    pose_prog: PoseProgram,
    // Combinational helpers.
    mul_go: Signal<Local, Bit>,
    mul_a_in: Signal<Local, Bits<26>>,
    mul_b_in: Signal<Local, Bits<18>>,
    div_go: Signal<Local, Bit>,
    div_n_in: Signal<Local, Bits<48>>,
    sel_centre: Signal<Local, Bits<24>>,
    sel_sigma: Signal<Local, Bits<22>>,
    sel_floor: Signal<Local, Bits<22>>,
    sel_cap: Signal<Local, Bits<22>>,
    sel_est: Signal<Local, Bits<24>>,
    rng_next: Signal<Local, Bits<32>>,
    u_hi: Signal<Local, Bits<16>>,
    ref24: Signal<Local, Bits<24>>,
    ex_now: Signal<Local, Bits<48>>,
    ex_masked: Signal<Local, Bits<48>>,
    est_v: Signal<Local, Bits<24>>,
    sig_new: Signal<Local, Bits<22>>,
    est_fix: Signal<Local, Bits<24>>,
    v_fix: Signal<Local, Bits<24>>,
    prod_sh14: Signal<Local, Bits<26>>,
    prod_sh15: Signal<Local, Bits<26>>,
    diff24: Signal<Local, Bits<24>>,
    diff26: Signal<Local, Bits<26>>,
    lim26: Signal<Local, Bits<26>>,
    neg_lim26: Signal<Local, Bits<26>>,
    v24: Signal<Local, Bits<24>>,
    ang: Signal<Local, Bits<24>>,
    tr_y: Signal<Local, Bits<25>>,
    tr_t: Signal<Local, Bits<19>>,
    tr_sat: Signal<Local, Bits<18>>,
    acc_abs: Signal<Local, Bits<48>>,
    q26: Signal<Local, Bits<26>>,
    mean26: Signal<Local, Bits<26>>,
    dev26: Signal<Local, Bits<26>>,
    abs26: Signal<Local, Bits<26>>,
    // Sign extensions, as a mux on the sign bit (no carry chain).
    u_hi_s18: Signal<Local, Bits<18>>,
    cor_v_s26: Signal<Local, Bits<26>>,
    scale_s26: Signal<Local, Bits<26>>,
    tr_in_s25: Signal<Local, Bits<25>>,
    tr_in: Signal<Local, Bits<24>>,
    maxd_next: Signal<Local, Bits<34>>,
    t_entry: Signal<Local, Bits<8>>,
    e_tmp: Signal<Local, Bits<6>>,
}

impl Default for PfSequencer {
    fn default() -> Self {
        Self::new()
    }
}

impl PfSequencer {
    /// After reset: idle, no result; the pose program, CORDIC angles and exp table in ROM.
    pub fn new() -> Self {
        PfSequencer {
            clock: Default::default(),
            reset: Default::default(),
            cfg_we: Default::default(),
            cfg_addr: Default::default(),
            cfg_data: Default::default(),
            go: Default::default(),
            nn_ready: Default::default(),
            cost_valid: Default::default(),
            cost: Default::default(),
            nn_valid: Default::default(),
            nn_dist: Default::default(),
            start: Default::default(),
            pose: Default::default(),
            running: Default::default(),
            finished: Default::default(),
            iterations: Default::default(),
            best_cost: Default::default(),
            best_max: Default::default(),
            params: Default::default(),
            p_we: Default::default(),
            p_waddr: Default::default(),
            p_wdata: Default::default(),
            centre: Default::default(),
            cap: Default::default(),
            floor: Default::default(),
            sigma: Default::default(),
            est: Default::default(),
            best: Default::default(),
            cur: Default::default(),
            n_part: Default::default(),
            n_iter: Default::default(),
            tq: Default::default(),
            seed: Default::default(),
            thr_cost: Default::default(),
            thr_max: Default::default(),
            state: Default::default(),
            ret: Default::default(),
            ret2: Default::default(),
            rng: Default::default(),
            k: Default::default(),
            iter_done: Default::default(),
            run_r: Default::default(),
            fin_r: Default::default(),
            first: Default::default(),
            half: Default::default(),
            i: Default::default(),
            j: Default::default(),
            pd: Default::default(),
            spread: Default::default(),
            pa: Default::default(),
            cra: Default::default(),
            wra: Default::default(),
            x_r: Default::default(),
            off: Default::default(),
            start_r: Default::default(),
            pose_r: Default::default(),
            maxd: Default::default(),
            costr: Default::default(),
            cmin: Default::default(),
            imin: Default::default(),
            best_cost_r: Default::default(),
            best_max_r: Default::default(),
            p: Default::default(),
            mask: Default::default(),
            cnt: Default::default(),
            pre: Default::default(),
            sh: Default::default(),
            w_sum: Default::default(),
            acc: Default::default(),
            lft: Default::default(),
            rgt: Default::default(),
            cj: Default::default(),
            all48: Constant::new(Bits::<48>::from((1u64 << 48) - 1)),
            sign44: Constant::new(Bits::<44>::from(1u64 << 43)),
            sign48_44: Constant::new(Bits::<48>::from(1u64 << 43)),
            pram: Default::default(),
            cram: Default::default(),
            wram: Default::default(),
            exp_rom: exp_table().iter().map(|&w| Bits::<16>::from(w as u64)).into(),
            mul: SerialMul::new(),
            div: SerialDiv::new(),
            xorshift: Xorshift32::new(),
            cordic: Cordic::new(),
            pose_prog: PoseProgram::new(),
            mul_go: Default::default(),
            mul_a_in: Default::default(),
            mul_b_in: Default::default(),
            div_go: Default::default(),
            div_n_in: Default::default(),
            sel_centre: Default::default(),
            sel_sigma: Default::default(),
            sel_floor: Default::default(),
            sel_cap: Default::default(),
            sel_est: Default::default(),
            rng_next: Default::default(),
            u_hi: Default::default(),
            ref24: Default::default(),
            ex_now: Default::default(),
            ex_masked: Default::default(),
            est_v: Default::default(),
            sig_new: Default::default(),
            est_fix: Default::default(),
            v_fix: Default::default(),
            prod_sh14: Default::default(),
            prod_sh15: Default::default(),
            diff24: Default::default(),
            diff26: Default::default(),
            lim26: Default::default(),
            neg_lim26: Default::default(),
            v24: Default::default(),
            ang: Default::default(),
            tr_y: Default::default(),
            tr_t: Default::default(),
            tr_sat: Default::default(),
            acc_abs: Default::default(),
            q26: Default::default(),
            mean26: Default::default(),
            dev26: Default::default(),
            abs26: Default::default(),
            u_hi_s18: Default::default(),
            cor_v_s26: Default::default(),
            scale_s26: Default::default(),
            tr_in_s25: Default::default(),
            tr_in: Default::default(),
            maxd_next: Default::default(),
            t_entry: Default::default(),
            e_tmp: Default::default(),
        }
    }
}
