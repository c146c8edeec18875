//! `PfSequencer`: the on-board particle filter (docs/sequencer.md), the RTL of
//! [`crate::pf::run`]. It owns the particle set (two halves of a 4,096 x 24 RAM), the
//! per-particle costs and weights, a serial multiplier (26 x 18 bits, 18 clocks), a serial
//! divider (48 / 24 bits, 48 clocks), a CORDIC (18 steps) and the pose program
//! ([`crate::pf::POSE_PROGRAM`] in ROM over a 32 x 26 register file). It drives the
//! nearest-neighbour pipeline through `start` / `pose` and listens to its results.
//!
//! Everything is sequential and small next to the pipeline's ~10^4 clocks per particle.
//! The cycle-accurate mirror is [`crate::sequencer::SequencerModel`].

use crate::format::exp_table;
use crate::pf::{CORDIC_ATAN, CORDIC_K, POSE_PROGRAM};
use rust_hdl::prelude::*;

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
    // Serial multiplier.
    m_a: DFF<Bits<44>>,
    m_b: DFF<Bits<18>>,
    m_acc: DFF<Bits<44>>,
    m_cnt: DFF<Bits<5>>,
    // Serial divider.
    dv_n: DFF<Bits<48>>,
    dv_d: DFF<Bits<24>>,
    dv_rem: DFF<Bits<25>>,
    dv_cnt: DFF<Bits<6>>,
    // CORDIC.
    cx: DFF<Bits<22>>,
    cy: DFF<Bits<22>>,
    cz: DFF<Bits<25>>,
    ci: DFF<Bits<5>>,
    cj: DFF<Bits<2>>,
    cflip: DFF<Bit>,
    // Pose program.
    pc: DFF<Bits<5>>,
    op_kind: DFF<Bits<2>>,
    op_dst: DFF<Bits<5>>,
    op_b: DFF<Bits<5>>,
    opa: DFF<Bits<26>>,
    all48: Constant<Bits<48>>,
    sign44: Constant<Bits<44>>,
    sign48_44: Constant<Bits<48>>,
    // Memories.
    pram: RAM<Bits<24>, 12>,
    cram: RAM<Bits<82>, 8>,
    wram: RAM<Bits<16>, 8>,
    rf: RAM<Bits<26>, 5>,
    prog: ROM<Bits<17>, 5>,
    atan: ROM<Bits<22>, 5>,
    exp_rom: ROM<Bits<16>, 8>,
    // Combinational helpers.
    mul_go: Signal<Local, Bit>,
    mul_a_in: Signal<Local, Bits<26>>,
    mul_b_in: Signal<Local, Bits<18>>,
    div_go: Signal<Local, Bit>,
    div_n_in: Signal<Local, Bits<48>>,
    rem2: Signal<Local, Bits<25>>,
    sel_centre: Signal<Local, Bits<24>>,
    sel_sigma: Signal<Local, Bits<22>>,
    sel_floor: Signal<Local, Bits<22>>,
    sel_cap: Signal<Local, Bits<22>>,
    sel_est: Signal<Local, Bits<24>>,
    sel_atan: Signal<Local, Bits<22>>,
    rng_next: Signal<Local, Bits<32>>,
    rng_t1: Signal<Local, Bits<32>>,
    rng_t2: Signal<Local, Bits<32>>,
    u_hi: Signal<Local, Bits<16>>,
    ref24: Signal<Local, Bits<24>>,
    ex_now: Signal<Local, Bits<48>>,
    ex_masked: Signal<Local, Bits<48>>,
    cor_sum: Signal<Local, Bits<22>>,
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
    ang_x: Signal<Local, Bits<24>>,
    cx_sh: Signal<Local, Bits<22>>,
    cy_sh: Signal<Local, Bits<22>>,
    ones22: Signal<Local, Bits<22>>,
    cor_out: Signal<Local, Bits<22>>,
    cor_r: Signal<Local, Bits<20>>,
    cor_v: Signal<Local, Bits<20>>,
    prog_word: Signal<Local, Bits<17>>,
    rf_b: Signal<Local, Bits<26>>,
    m_round16: Signal<Local, Bits<44>>,
    m_round22: Signal<Local, Bits<44>>,
    m_t22: Signal<Local, Bits<22>>,
    m_sat: Signal<Local, Bits<18>>,
    tr_y: Signal<Local, Bits<25>>,
    tr_t: Signal<Local, Bits<19>>,
    tr_sat: Signal<Local, Bits<18>>,
    m_neg: Signal<Local, Bits<44>>,
    acc_abs: Signal<Local, Bits<48>>,
    q26: Signal<Local, Bits<26>>,
    mean26: Signal<Local, Bits<26>>,
    dev26: Signal<Local, Bits<26>>,
    abs26: Signal<Local, Bits<26>>,
    // Sign extensions, as a mux on the sign bit (no carry chain).
    u_hi_s18: Signal<Local, Bits<18>>,
    cor_v_s26: Signal<Local, Bits<26>>,
    ang_s25: Signal<Local, Bits<25>>,
    ang_x_s25: Signal<Local, Bits<25>>,
    scale_s26: Signal<Local, Bits<26>>,
    tr_in_s25: Signal<Local, Bits<25>>,
    mul_a_s44: Signal<Local, Bits<44>>,
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
            m_a: Default::default(),
            m_b: Default::default(),
            m_acc: Default::default(),
            m_cnt: Default::default(),
            dv_n: Default::default(),
            dv_d: Default::default(),
            dv_rem: Default::default(),
            dv_cnt: Default::default(),
            cx: Default::default(),
            cy: Default::default(),
            cz: Default::default(),
            ci: Default::default(),
            cj: Default::default(),
            cflip: Default::default(),
            pc: Default::default(),
            op_kind: Default::default(),
            op_dst: Default::default(),
            op_b: Default::default(),
            opa: Default::default(),
            all48: Constant::new(Bits::<48>::from((1u64 << 48) - 1)),
            sign44: Constant::new(Bits::<44>::from(1u64 << 43)),
            sign48_44: Constant::new(Bits::<48>::from(1u64 << 43)),
            pram: Default::default(),
            cram: Default::default(),
            wram: Default::default(),
            rf: RAM::new((0..32u64).map(|a| (Bits::<5>::from(a), Bits::<26>::default())).collect()),
            prog: POSE_PROGRAM.iter().map(|op| Bits::<17>::from(op.encode() as u64)).into(),
            atan: CORDIC_ATAN.iter().map(|&t| Bits::<22>::from(t as u64)).into(),
            exp_rom: exp_table().iter().map(|&w| Bits::<16>::from(w as u64)).into(),
            mul_go: Default::default(),
            mul_a_in: Default::default(),
            mul_b_in: Default::default(),
            div_go: Default::default(),
            div_n_in: Default::default(),
            rem2: Default::default(),
            sel_centre: Default::default(),
            sel_sigma: Default::default(),
            sel_floor: Default::default(),
            sel_cap: Default::default(),
            sel_est: Default::default(),
            sel_atan: Default::default(),
            rng_next: Default::default(),
            rng_t1: Default::default(),
            rng_t2: Default::default(),
            u_hi: Default::default(),
            ref24: Default::default(),
            ex_now: Default::default(),
            ex_masked: Default::default(),
            cor_sum: Default::default(),
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
            ang_x: Default::default(),
            cx_sh: Default::default(),
            cy_sh: Default::default(),
            ones22: Default::default(),
            cor_out: Default::default(),
            cor_r: Default::default(),
            cor_v: Default::default(),
            prog_word: Default::default(),
            rf_b: Default::default(),
            m_round16: Default::default(),
            m_round22: Default::default(),
            m_t22: Default::default(),
            m_sat: Default::default(),
            tr_y: Default::default(),
            tr_t: Default::default(),
            tr_sat: Default::default(),
            m_neg: Default::default(),
            acc_abs: Default::default(),
            q26: Default::default(),
            mean26: Default::default(),
            dev26: Default::default(),
            abs26: Default::default(),
            u_hi_s18: Default::default(),
            cor_v_s26: Default::default(),
            ang_s25: Default::default(),
            ang_x_s25: Default::default(),
            scale_s26: Default::default(),
            tr_in_s25: Default::default(),
            mul_a_s44: Default::default(),
            tr_in: Default::default(),
            maxd_next: Default::default(),
            t_entry: Default::default(),
            e_tmp: Default::default(),
        }
    }
}

// Literals in the kernel (`#[hdl_gen]` takes no paths): keep them equal to the reference.
const _: () = assert!(CORDIC_K == 159188 && POSE_PROGRAM.len() == 28 && CORDIC_ATAN.len() == 18);

impl Logic for PfSequencer {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self,
            clock,
            n_part,
            n_iter,
            tq,
            seed,
            thr_cost,
            thr_max,
            state,
            ret,
            ret2,
            rng,
            k,
            iter_done,
            run_r,
            fin_r,
            first,
            half,
            i,
            j,
            pd,
            spread,
            pa,
            cra,
            wra,
            x_r,
            off,
            start_r,
            pose_r,
            maxd,
            costr,
            cmin,
            imin,
            best_cost_r,
            best_max_r,
            p,
            mask,
            cnt,
            pre,
            sh,
            w_sum,
            acc,
            lft,
            rgt,
            m_a,
            m_b,
            m_acc,
            m_cnt,
            dv_n,
            dv_d,
            dv_rem,
            dv_cnt,
            cx,
            cy,
            cz,
            ci,
            cj,
            cflip,
            pc,
            op_kind,
            op_dst,
            op_b,
            opa
        );
        for q in 0..7 {
            self.centre[q].clock.next = self.clock.val();
            self.centre[q].d.next = self.centre[q].q.val();
            self.cap[q].clock.next = self.clock.val();
            self.cap[q].d.next = self.cap[q].q.val();
            self.floor[q].clock.next = self.clock.val();
            self.floor[q].d.next = self.floor[q].q.val();
            self.sigma[q].clock.next = self.clock.val();
            self.sigma[q].d.next = self.sigma[q].q.val();
            self.est[q].clock.next = self.clock.val();
            self.est[q].d.next = self.est[q].q.val();
            self.best[q].clock.next = self.clock.val();
            self.best[q].d.next = self.best[q].q.val();
            self.cur[q].clock.next = self.clock.val();
            self.cur[q].d.next = self.cur[q].q.val();
        }
        self.pram.read_clock.next = self.clock.val();
        self.pram.write_clock.next = self.clock.val();
        self.cram.read_clock.next = self.clock.val();
        self.cram.write_clock.next = self.clock.val();
        self.wram.read_clock.next = self.clock.val();
        self.wram.write_clock.next = self.clock.val();
        self.rf.read_clock.next = self.clock.val();
        self.rf.write_clock.next = self.clock.val();

        // Outputs (all from registers).
        self.start.next = self.start_r.q.val();
        self.pose.next = self.pose_r.q.val();
        self.running.next = self.run_r.q.val();
        self.finished.next = self.fin_r.q.val();
        self.iterations.next = self.iter_done.q.val();
        self.best_cost.next = self.best_cost_r.q.val();
        self.best_max.next = self.best_max_r.q.val();
        self.params.next = bit_cast::<168, 24>(self.best[0].q.val())
            | (bit_cast::<168, 24>(self.best[1].q.val()) << 24)
            | (bit_cast::<168, 24>(self.best[2].q.val()) << 48)
            | (bit_cast::<168, 24>(self.best[3].q.val()) << 72)
            | (bit_cast::<168, 24>(self.best[4].q.val()) << 96)
            | (bit_cast::<168, 24>(self.best[5].q.val()) << 120)
            | (bit_cast::<168, 24>(self.best[6].q.val()) << 144);

        // Parameter `d` of the vectors.
        self.sel_centre.next = self.centre[0].q.val();
        self.sel_sigma.next = self.sigma[0].q.val();
        self.sel_floor.next = self.floor[0].q.val();
        self.sel_cap.next = self.cap[0].q.val();
        self.sel_est.next = self.est[0].q.val();
        for q in 1..7 {
            if self.pd.q.val().index() == q {
                self.sel_centre.next = self.centre[q].q.val();
                self.sel_sigma.next = self.sigma[q].q.val();
                self.sel_floor.next = self.floor[q].q.val();
                self.sel_cap.next = self.cap[q].q.val();
                self.sel_est.next = self.est[q].q.val();
            }
        }

        // PRNG: xorshift32 (13, 17, 5).
        self.rng_t1.next = self.rng.q.val() ^ (self.rng.q.val() << 13);
        self.rng_t2.next = self.rng_t1.val() ^ (self.rng_t1.val() >> 17);
        self.rng_next.next = self.rng_t2.val() ^ (self.rng_t2.val() << 5);
        self.u_hi.next = self.rng.q.val().get_bits::<16>(16);

        // Propagation arithmetic.
        self.prod_sh14.next = self.m_acc.q.val().get_bits::<26>(14);
        self.prod_sh15.next = self.m_acc.q.val().get_bits::<26>(15);
        self.ref24.next = self.sel_centre.val();
        if self.spread.q.val() {
            self.ref24.next = self.sel_est.val();
        }
        self.diff24.next = self.x_r.q.val() - self.ref24.val();
        self.diff26.next = bit_cast::<26, 24>(self.diff24.val());
        if self.diff24.val().get_bit(23) {
            self.diff26.next = bit_cast::<26, 24>(self.diff24.val()) | bits::<26>(0x300_0000);
        }
        self.lim26.next = bit_cast::<26, 22>(self.sel_sigma.val()) << 1;
        // Negations go through a Local: in a Verilog compare, `0 - x` would be 32 bits wide.
        self.neg_lim26.next = bits::<26>(0) - self.lim26.val();
        self.v24.next = self.sel_centre.val() + self.off.q.val().get_bits::<24>(0);
        self.v_fix.next = self.v24.val();
        if (self.pd.q.val() == 3) && (self.v24.val().get_bit(23) || !self.v24.val().any()) {
            self.v_fix.next = bits::<24>(1);
        }
        self.ex_now.next = self.cram.read_data.val().get_bits::<48>(0) - self.cmin.q.val();
        self.ex_masked.next = self.ex_now.val() & !self.mask.q.val();

        // CORDIC.
        self.ang.next = self.cur[4].q.val();
        if self.cj.q.val() == 1 {
            self.ang.next = self.cur[5].q.val();
        }
        if self.cj.q.val() == 2 {
            self.ang.next = self.cur[6].q.val();
        }
        self.ang_x.next = self.ang.val() ^ bits::<24>(0x80_0000);
        self.atan.address.next = self.ci.q.val();
        self.sel_atan.next = self.atan.data.val();
        self.ones22.next = bits::<22>(0x3f_ffff);
        self.cx_sh.next = self.cx.q.val() >> self.ci.q.val();
        if self.cx.q.val().get_bit(21) {
            self.cx_sh.next = (self.cx.q.val() >> self.ci.q.val()) | !(self.ones22.val() >> self.ci.q.val());
        }
        self.cy_sh.next = self.cy.q.val() >> self.ci.q.val();
        if self.cy.q.val().get_bit(21) {
            self.cy_sh.next = (self.cy.q.val() >> self.ci.q.val()) | !(self.ones22.val() >> self.ci.q.val());
        }
        self.cor_out.next = self.cx.q.val();
        if self.state.q.val() == SeqState::CorSin {
            self.cor_out.next = self.cy.q.val();
        }
        self.cor_sum.next = self.cor_out.val() + 2;
        self.cor_r.next = bit_cast::<20, 22>(self.cor_sum.val() >> 2);
        self.cor_v.next = self.cor_r.val();
        if self.cflip.q.val() {
            self.cor_v.next = bits::<20>(0) - self.cor_r.val();
        }

        // Pose program.
        self.prog.address.next = self.pc.q.val();
        self.prog_word.next = self.prog.data.val();
        self.rf_b.next = self.rf.read_data.val();
        self.m_round16.next = self.m_acc.q.val() + bits::<44>(0x8000);
        self.m_round22.next = self.m_acc.q.val() + bits::<44>(0x20_0000);
        self.m_t22.next = bit_cast::<22, 44>(self.m_round22.val() >> 22);
        self.m_sat.next = self.m_t22.val().get_bits::<18>(0);
        if (self.m_t22.val() ^ bits::<22>(0x20_0000)) > bits::<22>(0x21_ffff) {
            self.m_sat.next = bits::<18>(0x1_ffff);
        }
        if (self.m_t22.val() ^ bits::<22>(0x20_0000)) < bits::<22>(0x1e_0000) {
            self.m_sat.next = bits::<18>(0x2_0000);
        }
        self.tr_in.next = self.cur[0].q.val();
        if self.cj.q.val() == 1 {
            self.tr_in.next = self.cur[1].q.val();
        }
        if self.cj.q.val() == 2 {
            self.tr_in.next = self.cur[2].q.val();
        }
        self.tr_in_s25.next = bit_cast::<25, 24>(self.tr_in.val());
        if self.tr_in.val().get_bit(23) {
            self.tr_in_s25.next = bit_cast::<25, 24>(self.tr_in.val()) | bits::<25>(0x100_0000);
        }
        self.tr_y.next = self.tr_in_s25.val() + bits::<25>(32);
        self.tr_t.next = bit_cast::<19, 25>(self.tr_y.val() >> 6);
        self.tr_sat.next = self.tr_t.val().get_bits::<18>(0);
        if (self.tr_t.val() ^ bits::<19>(0x4_0000)) > bits::<19>(0x5_ffff) {
            self.tr_sat.next = bits::<18>(0x1_ffff);
        }
        if (self.tr_t.val() ^ bits::<19>(0x4_0000)) < bits::<19>(0x2_0000) {
            self.tr_sat.next = bits::<18>(0x2_0000);
        }

        // Estimate / spread arithmetic.
        self.acc_abs.next = self.acc.q.val();
        if self.acc.q.val().get_bit(47) {
            self.acc_abs.next = bits::<48>(0) - self.acc.q.val();
        }
        self.q26.next = self.dv_n.q.val().get_bits::<26>(0);
        self.mean26.next = self.q26.val();
        if self.acc.q.val().get_bit(47) {
            self.mean26.next = bits::<26>(0) - self.q26.val();
        }
        self.dev26.next = self.q26.val() + (self.q26.val() >> 2);
        self.sig_new.next = self.dev26.val().get_bits::<22>(0);
        if self.dev26.val() > bit_cast::<26, 22>(self.sel_cap.val()) {
            self.sig_new.next = self.sel_cap.val();
        }
        if self.dev26.val() < bit_cast::<26, 22>(self.sel_floor.val()) {
            self.sig_new.next = self.sel_floor.val();
        }
        self.est_v.next = self.sel_centre.val() + bit_cast::<24, 26>(self.mean26.val());
        self.est_fix.next = self.est_v.val();
        if (self.pd.q.val() == 3) && (self.est_v.val().get_bit(23) || !self.est_v.val().any()) {
            self.est_fix.next = bits::<24>(1);
        }
        self.abs26.next = self.diff26.val();
        if self.diff26.val().get_bit(25) {
            self.abs26.next = bits::<26>(0) - self.diff26.val();
        }
        self.maxd_next.next = self.maxd.q.val();
        if self.nn_valid.val() && (self.nn_dist.val() > self.maxd.q.val()) {
            self.maxd_next.next = self.nn_dist.val();
        }
        self.t_entry.next = self.sh.q.val().get_bits::<8>(0);
        if self.sh.q.val() > 255 {
            self.t_entry.next = bits::<8>(255);
        }
        self.exp_rom.address.next = self.t_entry.val();
        self.e_tmp.next = self.tq.q.val();
        if (self.p.q.val() > 2) && ((self.p.q.val() - 2) > self.tq.q.val()) {
            self.e_tmp.next = self.p.q.val() - 2;
        }

        // Sign extensions (a mux on the sign bit, so no carry chain lengthens a path).
        self.u_hi_s18.next = bit_cast::<18, 16>(self.u_hi.val());
        if self.u_hi.val().get_bit(15) {
            self.u_hi_s18.next = bit_cast::<18, 16>(self.u_hi.val()) | bits::<18>(0x3_0000);
        }
        self.cor_v_s26.next = bit_cast::<26, 20>(self.cor_v.val());
        if self.cor_v.val().get_bit(19) {
            self.cor_v_s26.next = bit_cast::<26, 20>(self.cor_v.val()) | bits::<26>(0x3f0_0000);
        }
        self.ang_s25.next = bit_cast::<25, 24>(self.ang.val());
        if self.ang.val().get_bit(23) {
            self.ang_s25.next = bit_cast::<25, 24>(self.ang.val()) | bits::<25>(0x100_0000);
        }
        self.ang_x_s25.next = bit_cast::<25, 24>(self.ang_x.val());
        if self.ang_x.val().get_bit(23) {
            self.ang_x_s25.next = bit_cast::<25, 24>(self.ang_x.val()) | bits::<25>(0x100_0000);
        }
        self.scale_s26.next = bit_cast::<26, 24>(self.cur[3].q.val());
        if self.cur[3].q.val().get_bit(23) {
            self.scale_s26.next = bit_cast::<26, 24>(self.cur[3].q.val()) | bits::<26>(0x300_0000);
        }

        // Memory defaults.
        self.pram.read_address.next = self.pa.q.val();
        self.pram.write_enable.next = false;
        self.pram.write_address.next = self.pa.q.val();
        self.pram.write_data.next = self.v_fix.val();
        self.cram.read_address.next = self.cra.q.val();
        self.cram.write_enable.next = false;
        self.cram.write_address.next = self.i.q.val().get_bits::<8>(0);
        self.cram.write_data.next =
            bit_cast::<82, 48>(self.costr.q.val()) | (bit_cast::<82, 34>(self.maxd.q.val()) << 48);
        self.wram.read_address.next = self.wra.q.val();
        self.wram.write_enable.next = false;
        self.wram.write_address.next = self.i.q.val().get_bits::<8>(0);
        self.wram.write_data.next = self.exp_rom.data.val();
        self.rf.read_address.next = self.op_b.q.val();
        self.rf.write_enable.next = false;
        self.rf.write_address.next = self.op_dst.q.val();
        self.rf.write_data.next = self.cor_v_s26.val();
        self.start_r.d.next = false;
        self.mul_go.next = false;
        self.mul_a_in.next = bit_cast::<26, 22>(self.sel_sigma.val());
        self.mul_b_in.next = self.u_hi_s18.val();
        self.div_go.next = false;
        self.div_n_in.next = self.acc_abs.val();

        // Configuration writes.
        if self.cfg_we.val() {
            for q in 0..7 {
                if self.cfg_addr.val().index() == q {
                    self.centre[q].d.next = self.cfg_data.val().get_bits::<24>(0);
                }
                if self.cfg_addr.val().index() == (q + 7) {
                    self.cap[q].d.next = self.cfg_data.val().get_bits::<22>(0);
                }
                if self.cfg_addr.val().index() == (q + 14) {
                    self.floor[q].d.next = self.cfg_data.val().get_bits::<22>(0);
                }
            }
            if self.cfg_addr.val() == 21 {
                self.seed.d.next = self.cfg_data.val().get_bits::<32>(0);
            }
            if self.cfg_addr.val() == 22 {
                self.thr_cost.d.next = self.cfg_data.val();
            }
            if self.cfg_addr.val() == 23 {
                self.thr_max.d.next = self.cfg_data.val().get_bits::<34>(0);
            }
            if self.cfg_addr.val() == 24 {
                self.n_part.d.next = self.cfg_data.val().get_bits::<9>(0);
                self.n_iter.d.next = self.cfg_data.val().get_bits::<16>(16);
                self.tq.d.next = self.cfg_data.val().get_bits::<6>(32);
            }
        }

        match self.state.q.val() {
            SeqState::Idle => {
                if self.go.val() {
                    for q in 0..7 {
                        self.sigma[q].d.next = self.cap[q].q.val();
                        if self.floor[q].q.val() > self.cap[q].q.val() {
                            self.cap[q].d.next = self.floor[q].q.val();
                            self.sigma[q].d.next = self.floor[q].q.val();
                        }
                        self.cur[q].d.next = self.centre[q].q.val();
                    }
                    self.rng.d.next = self.seed.q.val();
                    if !self.seed.q.val().any() {
                        self.rng.d.next = bits::<32>(1);
                    }
                    self.run_r.d.next = true;
                    self.fin_r.d.next = false;
                    // Nothing evaluated yet: Status reports no best cost (not the last run's).
                    self.best_cost_r.d.next = self.all48.val();
                    self.iter_done.d.next = 0.into();
                    self.k.d.next = 0.into();
                    self.half.d.next = 0.into();
                    self.cj.d.next = 0.into();
                    self.ret.d.next = SeqState::EvStart;
                    self.ret2.d.next = SeqState::StartDone;
                    self.state.d.next = SeqState::CorInit;
                }
            }
            // ---- Pose subroutine: `cur` -> `pose_r`, then `ret`.
            SeqState::CorInit => {
                self.cx.d.next = bits::<22>(159188);
                self.cy.d.next = 0.into();
                self.ci.d.next = 0.into();
                self.cflip.d.next = false;
                self.cz.d.next = self.ang_s25.val();
                if (self.ang_x.val() > bits::<24>(0xc0_0000)) || (self.ang_x.val() < bits::<24>(0x40_0000)) {
                    self.cflip.d.next = true;
                    self.cz.d.next = self.ang_x_s25.val();
                }
                self.state.d.next = SeqState::CorStep;
            }
            SeqState::CorStep => {
                if !self.cz.q.val().get_bit(24) {
                    self.cx.d.next = self.cx.q.val() - self.cy_sh.val();
                    self.cy.d.next = self.cy.q.val() + self.cx_sh.val();
                    self.cz.d.next = self.cz.q.val() - bit_cast::<25, 22>(self.sel_atan.val());
                } else {
                    self.cx.d.next = self.cx.q.val() + self.cy_sh.val();
                    self.cy.d.next = self.cy.q.val() - self.cx_sh.val();
                    self.cz.d.next = self.cz.q.val() + bit_cast::<25, 22>(self.sel_atan.val());
                }
                self.ci.d.next = self.ci.q.val() + 1;
                if self.ci.q.val() == 17 {
                    self.state.d.next = SeqState::CorCos;
                }
            }
            SeqState::CorCos => {
                self.rf.write_enable.next = true;
                self.rf.write_address.next = bit_cast::<5, 2>(self.cj.q.val()) << 1;
                self.state.d.next = SeqState::CorSin;
            }
            SeqState::CorSin => {
                self.rf.write_enable.next = true;
                self.rf.write_address.next = (bit_cast::<5, 2>(self.cj.q.val()) << 1) + 1;
                self.cj.d.next = self.cj.q.val() + 1;
                if self.cj.q.val() == 2 {
                    self.state.d.next = SeqState::PoseScale;
                } else {
                    self.state.d.next = SeqState::CorInit;
                }
            }
            SeqState::PoseScale => {
                self.rf.write_enable.next = true;
                self.rf.write_address.next = bits::<5>(6);
                self.rf.write_data.next = self.scale_s26.val();
                self.pc.d.next = 0.into();
                self.cj.d.next = 0.into();
                self.state.d.next = SeqState::OpFetch;
            }
            SeqState::OpFetch => {
                self.rf.read_address.next = self.prog_word.val().get_bits::<5>(7);
                self.op_kind.d.next = self.prog_word.val().get_bits::<2>(0);
                self.op_dst.d.next = self.prog_word.val().get_bits::<5>(2);
                self.op_b.d.next = self.prog_word.val().get_bits::<5>(12);
                self.state.d.next = SeqState::OpA;
            }
            SeqState::OpA => {
                self.opa.d.next = self.rf.read_data.val();
                self.state.d.next = SeqState::OpB;
            }
            SeqState::OpB => {
                if self.op_kind.q.val().get_bit(1) {
                    self.rf.write_enable.next = true;
                    if self.op_kind.q.val().get_bit(0) {
                        self.rf.write_data.next = self.opa.q.val() - self.rf_b.val();
                    } else {
                        self.rf.write_data.next = self.opa.q.val() + self.rf_b.val();
                    }
                    self.pc.d.next = self.pc.q.val() + 1;
                    self.state.d.next = SeqState::OpFetch;
                } else {
                    self.mul_go.next = true;
                    self.mul_a_in.next = self.opa.q.val();
                    self.mul_b_in.next = self.rf_b.val().get_bits::<18>(0);
                    self.state.d.next = SeqState::OpMul;
                }
            }
            SeqState::OpMul => {
                if !self.m_cnt.q.val().any() {
                    if self.op_kind.q.val().get_bit(0) {
                        self.pose_r.d.next =
                            (self.pose_r.q.val() >> 18) | (bit_cast::<216, 18>(self.m_sat.val()) << 198);
                    } else {
                        self.rf.write_enable.next = true;
                        self.rf.write_data.next = bit_cast::<26, 44>(self.m_round16.val() >> 16);
                    }
                    self.pc.d.next = self.pc.q.val() + 1;
                    if self.pc.q.val() == 27 {
                        self.state.d.next = SeqState::PoseT;
                    } else {
                        self.state.d.next = SeqState::OpFetch;
                    }
                }
            }
            SeqState::PoseT => {
                self.pose_r.d.next = (self.pose_r.q.val() >> 18) | (bit_cast::<216, 18>(self.tr_sat.val()) << 198);
                self.cj.d.next = self.cj.q.val() + 1;
                if self.cj.q.val() == 2 {
                    self.state.d.next = self.ret.q.val();
                }
            }
            // ---- Evaluate subroutine: the pipeline on `pose_r`, then `ret2`.
            SeqState::EvStart => {
                if self.nn_ready.val() {
                    self.start_r.d.next = true;
                    self.maxd.d.next = 0.into();
                    self.state.d.next = SeqState::EvWait;
                }
            }
            SeqState::EvWait => {
                self.maxd.d.next = self.maxd_next.val();
                if self.cost_valid.val() {
                    self.costr.d.next = self.cost.val();
                    self.state.d.next = self.ret2.q.val();
                }
            }
            SeqState::StartDone => {
                self.best_cost_r.d.next = self.costr.q.val();
                self.best_max_r.d.next = self.maxd.q.val();
                for q in 0..7 {
                    self.best[q].d.next = self.cur[q].q.val();
                }
                self.state.d.next = SeqState::IterBegin;
            }
            // ---- One iteration.
            SeqState::IterBegin => {
                self.i.d.next = 0.into();
                self.pd.d.next = 0.into();
                self.cmin.d.next = self.all48.val();
                self.imin.d.next = 0.into();
                self.first.d.next = !self.k.q.val().any();
                self.pa.d.next = bit_cast::<12, 1>(self.half.q.val()) << 11;
                self.state.d.next = SeqState::PropAddr;
            }
            SeqState::PropAddr => {
                self.rng.d.next = self.rng_next.val();
                self.state.d.next = SeqState::PropRead;
            }
            SeqState::PropRead => {
                self.mul_go.next = true;
                self.state.d.next = SeqState::PropMul;
            }
            SeqState::PropMul => {
                self.x_r.d.next = self.pram.read_data.val();
                if !self.m_cnt.q.val().any() {
                    if self.first.q.val() {
                        self.off.d.next = self.prod_sh14.val();
                    } else {
                        self.off.d.next = self.diff26.val() + self.prod_sh15.val();
                    }
                    self.state.d.next = SeqState::PropClamp;
                }
            }
            SeqState::PropClamp => {
                if (self.off.q.val() ^ bits::<26>(0x200_0000)) > (self.lim26.val() ^ bits::<26>(0x200_0000)) {
                    self.off.d.next = self.lim26.val();
                }
                if (self.off.q.val() ^ bits::<26>(0x200_0000)) < (self.neg_lim26.val() ^ bits::<26>(0x200_0000)) {
                    self.off.d.next = self.neg_lim26.val();
                }
                self.state.d.next = SeqState::PropWrite;
            }
            SeqState::PropWrite => {
                self.pram.write_enable.next = true;
                for q in 0..7 {
                    if self.pd.q.val().index() == q {
                        self.cur[q].d.next = self.v_fix.val();
                    }
                }
                self.pa.d.next = self.pa.q.val() + 1;
                self.pd.d.next = self.pd.q.val() + 1;
                if self.pd.q.val() == 6 {
                    self.pd.d.next = 0.into();
                    self.pa.d.next = self.pa.q.val() + 2;
                    self.cj.d.next = 0.into();
                    self.ret.d.next = SeqState::EvStart;
                    self.ret2.d.next = SeqState::PartStore;
                    self.state.d.next = SeqState::CorInit;
                } else {
                    self.state.d.next = SeqState::PropAddr;
                }
            }
            SeqState::PartStore => {
                self.cram.write_enable.next = true;
                if self.costr.q.val() < self.cmin.q.val() {
                    self.cmin.d.next = self.costr.q.val();
                    self.imin.d.next = self.i.q.val().get_bits::<8>(0);
                }
                self.i.d.next = self.i.q.val() + 1;
                if (self.i.q.val() + 1) == self.n_part.q.val() {
                    self.p.d.next = 0.into();
                    self.mask.d.next = 0.into();
                    self.state.d.next = SeqState::TPass;
                } else {
                    self.state.d.next = SeqState::PropAddr;
                }
            }
            // ---- Temperature: the bit length of the excess of rank n / 2.
            SeqState::TPass => {
                self.i.d.next = 0.into();
                self.cnt.d.next = 0.into();
                self.state.d.next = SeqState::TAddr;
            }
            SeqState::TAddr => {
                self.cra.d.next = self.i.q.val().get_bits::<8>(0);
                self.state.d.next = SeqState::TWait;
            }
            SeqState::TWait => {
                self.state.d.next = SeqState::TData;
            }
            SeqState::TData => {
                if !self.ex_masked.val().any() {
                    self.cnt.d.next = self.cnt.q.val() + 1;
                }
                self.i.d.next = self.i.q.val() + 1;
                if (self.i.q.val() + 1) == self.n_part.q.val() {
                    self.state.d.next = SeqState::TCheck;
                } else {
                    self.state.d.next = SeqState::TAddr;
                }
            }
            SeqState::TCheck => {
                if self.cnt.q.val() > (self.n_part.q.val() >> 1) {
                    self.state.d.next = SeqState::TSet;
                } else {
                    self.p.d.next = self.p.q.val() + 1;
                    self.mask.d.next = (self.mask.q.val() << 1) | bits::<48>(1);
                    self.state.d.next = SeqState::TPass;
                }
            }
            SeqState::TSet => {
                self.pre.d.next = 0.into();
                if self.e_tmp.val() > 5 {
                    self.pre.d.next = self.e_tmp.val() - 5;
                }
                self.i.d.next = 0.into();
                self.w_sum.d.next = 0.into();
                self.state.d.next = SeqState::WAddr;
            }
            // ---- Weights.
            SeqState::WAddr => {
                self.cra.d.next = self.i.q.val().get_bits::<8>(0);
                self.state.d.next = SeqState::WWait;
            }
            SeqState::WWait => {
                self.state.d.next = SeqState::WData;
            }
            SeqState::WData => {
                self.sh.d.next = self.ex_now.val() >> self.pre.q.val();
                self.state.d.next = SeqState::WIdx;
            }
            SeqState::WIdx => {
                self.wram.write_enable.next = true;
                self.w_sum.d.next = self.w_sum.q.val() + bit_cast::<24, 16>(self.exp_rom.data.val());
                self.i.d.next = self.i.q.val() + 1;
                if (self.i.q.val() + 1) == self.n_part.q.val() {
                    self.state.d.next = SeqState::BestCheck;
                } else {
                    self.state.d.next = SeqState::WAddr;
                }
            }
            // ---- The best particle.
            SeqState::BestCheck => {
                self.cra.d.next = self.imin.q.val();
                self.pd.d.next = 0.into();
                if self.cmin.q.val() < self.best_cost_r.q.val() {
                    self.state.d.next = SeqState::BestRec;
                } else {
                    self.spread.d.next = false;
                    self.state.d.next = SeqState::SumBegin;
                }
            }
            SeqState::BestRec => {
                // The cost record of `imin` is on the RAM's output from this clock on.
                self.pa.d.next =
                    (bit_cast::<12, 1>(self.half.q.val()) << 11) | (bit_cast::<12, 8>(self.imin.q.val()) << 3);
                self.state.d.next = SeqState::BestAddr;
            }
            SeqState::BestAddr => {
                self.best_cost_r.d.next = self.cram.read_data.val().get_bits::<48>(0);
                self.best_max_r.d.next = self.cram.read_data.val().get_bits::<34>(48);
                self.state.d.next = SeqState::BestWait;
            }
            SeqState::BestWait => {
                self.state.d.next = SeqState::BestData;
            }
            SeqState::BestData => {
                for q in 0..7 {
                    if self.pd.q.val().index() == q {
                        self.best[q].d.next = self.pram.read_data.val();
                    }
                }
                self.pa.d.next = self.pa.q.val() + 1;
                self.pd.d.next = self.pd.q.val() + 1;
                if self.pd.q.val() == 6 {
                    self.pd.d.next = 0.into();
                    self.spread.d.next = false;
                    self.state.d.next = SeqState::SumBegin;
                } else {
                    self.state.d.next = SeqState::BestWait;
                }
            }
            // ---- Estimate (spread = 0) and spread (spread = 1), parameter d.
            SeqState::SumBegin => {
                self.acc.d.next = 0.into();
                self.i.d.next = 0.into();
                self.state.d.next = SeqState::SumAddr;
            }
            SeqState::SumAddr => {
                self.pa.d.next = (bit_cast::<12, 1>(self.half.q.val()) << 11)
                    | (bit_cast::<12, 8>(self.i.q.val().get_bits::<8>(0)) << 3)
                    | bit_cast::<12, 3>(self.pd.q.val());
                self.wra.d.next = self.i.q.val().get_bits::<8>(0);
                self.state.d.next = SeqState::SumWait;
            }
            SeqState::SumWait => {
                self.state.d.next = SeqState::SumData;
            }
            SeqState::SumData => {
                self.x_r.d.next = self.pram.read_data.val();
                self.state.d.next = SeqState::SumMul;
            }
            SeqState::SumMul => {
                // First clock here: start the multiply (x_r is the particle's parameter).
                self.state.d.next = SeqState::SumDiv;
                self.mul_go.next = true;
                self.mul_b_in.next = bit_cast::<18, 16>(self.wram.read_data.val());
                if self.spread.q.val() {
                    self.mul_a_in.next = self.abs26.val();
                } else {
                    self.mul_a_in.next = self.diff26.val();
                }
            }
            SeqState::SumDiv => {
                if !self.m_cnt.q.val().any() {
                    self.acc.d.next = self.acc.q.val()
                        + (bit_cast::<48, 44>(self.m_acc.q.val() ^ self.sign44.val()) - self.sign48_44.val());
                    self.i.d.next = self.i.q.val() + 1;
                    if (self.i.q.val() + 1) == self.n_part.q.val() {
                        self.state.d.next = SeqState::SumDivGo;
                    } else {
                        self.state.d.next = SeqState::SumAddr;
                    }
                }
            }
            SeqState::SumDivGo => {
                self.div_go.next = true;
                self.state.d.next = SeqState::SumDivWait;
            }
            SeqState::SumDivWait => {
                if !self.dv_cnt.q.val().any() {
                    for q in 0..7 {
                        if self.pd.q.val().index() == q {
                            if self.spread.q.val() {
                                self.sigma[q].d.next = self.sig_new.val();
                            } else {
                                self.est[q].d.next = self.est_fix.val();
                            }
                        }
                    }
                    self.pd.d.next = self.pd.q.val() + 1;
                    self.state.d.next = SeqState::SumBegin;
                    if self.pd.q.val() == 6 {
                        self.pd.d.next = 0.into();
                        if self.spread.q.val() {
                            self.state.d.next = SeqState::EstEval;
                        } else {
                            self.spread.d.next = true;
                        }
                    }
                }
            }
            SeqState::EstEval => {
                self.spread.d.next = false;
                for q in 0..7 {
                    self.cur[q].d.next = self.est[q].q.val();
                }
                self.cj.d.next = 0.into();
                self.ret.d.next = SeqState::EvStart;
                self.ret2.d.next = SeqState::EstDone;
                self.state.d.next = SeqState::CorInit;
            }
            SeqState::EstDone => {
                if self.costr.q.val() < self.best_cost_r.q.val() {
                    self.best_cost_r.d.next = self.costr.q.val();
                    self.best_max_r.d.next = self.maxd.q.val();
                    for q in 0..7 {
                        self.best[q].d.next = self.est[q].q.val();
                    }
                }
                self.state.d.next = SeqState::Centre;
            }
            SeqState::Centre => {
                for q in 0..7 {
                    self.centre[q].d.next = self.best[q].q.val();
                }
                self.iter_done.d.next = self.k.q.val() + 1;
                self.state.d.next = SeqState::StopCheck;
            }
            SeqState::StopCheck => {
                if ((self.best_cost_r.q.val() <= self.thr_cost.q.val())
                    && (self.best_max_r.q.val() <= self.thr_max.q.val()))
                    || (self.iter_done.q.val() == self.n_iter.q.val())
                {
                    self.state.d.next = SeqState::Fin;
                } else {
                    self.rng.d.next = self.rng_next.val();
                    self.state.d.next = SeqState::RsBegin;
                }
            }
            // ---- Systematic resampling into the other half.
            SeqState::RsBegin => {
                self.mul_go.next = true;
                self.mul_a_in.next = bit_cast::<26, 24>(self.w_sum.q.val());
                self.mul_b_in.next = bit_cast::<18, 16>(self.u_hi.val());
                self.wra.d.next = 0.into();
                self.i.d.next = 0.into();
                self.j.d.next = 0.into();
                self.rgt.d.next = 0.into();
                self.state.d.next = SeqState::RsL;
            }
            SeqState::RsL => {
                if !self.m_cnt.q.val().any() {
                    self.lft.d.next = bit_cast::<50, 44>(self.m_acc.q.val());
                    self.state.d.next = SeqState::RsWData;
                }
            }
            SeqState::RsWAddr => {
                self.wra.d.next = self.i.q.val().get_bits::<8>(0);
                self.state.d.next = SeqState::RsWWait;
            }
            SeqState::RsWWait => {
                self.state.d.next = SeqState::RsWData;
            }
            SeqState::RsWData => {
                self.mul_go.next = true;
                self.mul_a_in.next = bit_cast::<26, 9>(self.n_part.q.val());
                self.mul_b_in.next = bit_cast::<18, 16>(self.wram.read_data.val());
                self.state.d.next = SeqState::RsWMul;
            }
            SeqState::RsWMul => {
                if !self.m_cnt.q.val().any() {
                    self.rgt.d.next = self.rgt.q.val() + (bit_cast::<50, 44>(self.m_acc.q.val()) << 16);
                    self.state.d.next = SeqState::RsLoop;
                }
            }
            SeqState::RsLoop => {
                if (self.lft.q.val() > self.rgt.q.val()) && ((self.i.q.val() + 1) < self.n_part.q.val()) {
                    self.i.d.next = self.i.q.val() + 1;
                    self.state.d.next = SeqState::RsWAddr;
                } else {
                    self.pd.d.next = 0.into();
                    self.pa.d.next = (bit_cast::<12, 1>(self.half.q.val()) << 11)
                        | (bit_cast::<12, 8>(self.i.q.val().get_bits::<8>(0)) << 3);
                    self.state.d.next = SeqState::CpWait;
                }
            }
            SeqState::CpWait => {
                self.state.d.next = SeqState::CpData;
            }
            SeqState::CpData => {
                self.pram.write_enable.next = true;
                self.pram.write_address.next = (bit_cast::<12, 1>(!self.half.q.val()) << 11)
                    | (bit_cast::<12, 8>(self.j.q.val().get_bits::<8>(0)) << 3)
                    | bit_cast::<12, 3>(self.pd.q.val());
                self.pram.write_data.next = self.pram.read_data.val();
                self.pa.d.next = self.pa.q.val() + 1;
                self.pd.d.next = self.pd.q.val() + 1;
                if self.pd.q.val() == 6 {
                    self.state.d.next = SeqState::CpNext;
                } else {
                    self.state.d.next = SeqState::CpWait;
                }
            }
            SeqState::CpNext => {
                self.lft.d.next = self.lft.q.val() + (bit_cast::<50, 24>(self.w_sum.q.val()) << 16);
                self.j.d.next = self.j.q.val() + 1;
                if (self.j.q.val() + 1) == self.n_part.q.val() {
                    self.state.d.next = SeqState::RsDone;
                } else {
                    self.state.d.next = SeqState::RsLoop;
                }
            }
            SeqState::RsDone => {
                self.half.d.next = !self.half.q.val();
                self.k.d.next = self.k.q.val() + 1;
                self.state.d.next = SeqState::IterBegin;
            }
            SeqState::Fin => {
                for q in 0..7 {
                    self.cur[q].d.next = self.best[q].q.val();
                }
                self.cj.d.next = 0.into();
                self.ret.d.next = SeqState::FinDone;
                self.state.d.next = SeqState::CorInit;
            }
            SeqState::FinDone => {
                self.run_r.d.next = false;
                self.fin_r.d.next = true;
                self.state.d.next = SeqState::Idle;
            }
            _ => {
                self.state.d.next = SeqState::Idle;
            }
        }

        // The multiplicand, sign-extended (after the states have chosen it).
        self.mul_a_s44.next = bit_cast::<44, 26>(self.mul_a_in.val());
        if self.mul_a_in.val().get_bit(25) {
            self.mul_a_s44.next = bit_cast::<44, 26>(self.mul_a_in.val()) | !bits::<44>(0x3ff_ffff);
        }
        // The serial multiplier: 18 clocks, `m_acc = a * b` (b two's complement, its bit 17
        // weighs -2^17).
        self.m_neg.next = bits::<44>(0) - self.m_a.q.val();
        if self.mul_go.val() {
            self.m_a.d.next = self.mul_a_s44.val();
            self.m_b.d.next = self.mul_b_in.val();
            self.m_acc.d.next = 0.into();
            self.m_cnt.d.next = bits::<5>(18);
        } else if self.m_cnt.q.val().any() {
            if self.m_b.q.val().get_bit(0) {
                if self.m_cnt.q.val() == 1 {
                    self.m_acc.d.next = self.m_acc.q.val() + self.m_neg.val();
                } else {
                    self.m_acc.d.next = self.m_acc.q.val() + self.m_a.q.val();
                }
            }
            self.m_a.d.next = self.m_a.q.val() << 1;
            self.m_b.d.next = self.m_b.q.val() >> 1;
            self.m_cnt.d.next = self.m_cnt.q.val() - 1;
        }
        // The serial divider: 48 clocks, `dv_n = n / w_sum` (restoring).
        self.rem2.next = (self.dv_rem.q.val() << 1) | bit_cast::<25, 1>(self.dv_n.q.val().get_bits::<1>(47));
        if self.div_go.val() {
            self.dv_n.d.next = self.div_n_in.val();
            self.dv_d.d.next = self.w_sum.q.val();
            self.dv_rem.d.next = 0.into();
            self.dv_cnt.d.next = bits::<6>(48);
        } else if self.dv_cnt.q.val().any() {
            if self.rem2.val() >= bit_cast::<25, 24>(self.dv_d.q.val()) {
                self.dv_rem.d.next = self.rem2.val() - bit_cast::<25, 24>(self.dv_d.q.val());
                self.dv_n.d.next = (self.dv_n.q.val() << 1) | bits::<48>(1);
            } else {
                self.dv_rem.d.next = self.rem2.val();
                self.dv_n.d.next = self.dv_n.q.val() << 1;
            }
            self.dv_cnt.d.next = self.dv_cnt.q.val() - 1;
        }

        self.p_we.next = self.pram.write_enable.val();
        self.p_waddr.next = self.pram.write_address.val();
        self.p_wdata.next = self.pram.write_data.val();

        if self.reset.val() {
            self.state.d.next = SeqState::Idle;
            self.run_r.d.next = false;
            self.fin_r.d.next = false;
            self.m_cnt.d.next = 0.into();
            self.dv_cnt.d.next = 0.into();
        }
    }
}
