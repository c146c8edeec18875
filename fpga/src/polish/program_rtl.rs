//! `PolishProgram`: the datapath that runs [`crate::polish::program`] programs (a ROM of
//! several, [`crate::polish::program::Rom`], each started at its entry) over 64 x 128-bit
//! registers, the RTL twin of [`crate::polish::program::run`] (test:
//! `fpga/tests/polish_program.rs`, against the model on each of the polish's programs). The
//! ROM is synchronous (block RAM): its address is the next program counter, so the word
//! at the program counter is there when `fetch` needs it.
//!
//! No DSP48A1, and no carry chain longer than 48 bits, so that the block stays within the
//! board's 20 logic levels (docs/polish-datapath.md, "The datapath"):
//! - **one 128-bit adder in four 32-bit segments**, each segment's carry in from a
//!   register (`car`): `Alu` adds the operands, `Flush` adds the pending carries until none
//!   is left; the 129-bit result's sign in `sign`. The operand selects and inversions are
//!   registers (`sa`, `sb`, `ia`, `ib`, `ci`) set by the state before, so no decode sits in
//!   front of the chain;
//! - **the multiply on the same adder**, radix 4 (Booth): two multiplier bits a clock,
//!   `acc` plus 0, `x`, `2 x`, `-x` or `-2 x` with the segment carries left pending, until
//!   the rest of the signed multiplier gives only zero digits, one flush at the end;
//! - **a restoring divider** over a divisor of at most 64 bits
//!   ([`crate::polish::program::DIVISOR_BITS`]): the 65-bit trial subtract in two 33-bit
//!   halves, a clock a quotient bit (the next bit's low half computed for either outcome
//!   beside this bit's high half; the first bit's low half a clock of its own), the
//!   dividend shifting out of `acc` as the quotient shifts in; the dividend's leading zeros
//!   eight a clock (`DivSkip`);
//! - **shifts eight bits a clock** while more than eight remain (a shift left: eight or
//!   more), then one a clock (a product's rounding, a shift right, a constant's or a
//!   dividend's shift left);
//! - **the add port's own 48-bit adder** ([`crate::polish::program::add_port`]), one add a
//!   clock.
//!
//! An add instruction takes `fetch`, `operand`, `exec`, `alu`, `flush` and `write` (a clock
//! more for each segment a carry still has to cross); the others add their unit's clocks.
//!
//! This file holds the states, ports, registers, ROM and register file; the clocked logic
//! (one `update`) is `program_kernel_rtl.rs`.

use crate::polish::program::PROGRAM_WORDS;
use rust_hdl::prelude::*;

#[path = "program_kernel_rtl.rs"]
mod kernel;

/// Where the datapath is in an instruction.
#[derive(Copy, Clone, Debug, PartialEq, Eq, LogicState)]
pub enum ProgramState {
    /// Not running: `load` writes registers, `read_addr` reads them, `add` adds to them.
    Idle,
    /// Latch the instruction at the program counter; read its first operand.
    Fetch,
    /// Latch the first operand; read the second (held until the instruction ends).
    Operand,
    /// Execute: an add of the operands, or start the instruction's unit.
    Exec,
    /// The adder on the operands set by the state before; then `Flush`.
    Alu,
    /// Add the pending segment carries into `acc` until none is left; then the state in
    /// `ret`.
    Flush,
    /// Multiply, two multiplier bits a clock into `acc` with the segment carries pending.
    Mul,
    /// Arithmetic right shifts (a multiply's rounding, a shift).
    Round,
    /// Left shifts (a dividend's, a constant's).
    ShiftLeft,
    /// The dividend's magnitude is in `acc`: start the division (the quotient shifts into
    /// `acc` as the dividend shifts out).
    DivStart,
    /// Eight leading zero bits of the dividend a clock (their quotient bits are zero).
    DivSkip,
    /// The first quotient bit's trial subtract, the low half.
    DivLo,
    /// A quotient bit's high half and the bit; the next bit's low half.
    DivHi,
    /// `x - B - 1` is done: above the bound (the result is `B`), or test the low bound.
    ClampTest,
    /// `x + B` (a saturation's `x + B + 1`) is done: below the low bound (the result is
    /// `-B`, a saturation's `-B - 1`), or the result is `x`.
    ClampLow,
    /// `2 r[a] - r[b]` is done: fail below.
    StopTest,
    /// Write the result; the next instruction or the end.
    Write,
}

/// The program's datapath.
#[derive(LogicBlock)]
pub struct PolishProgram {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset: stop, idle.
    pub reset: Signal<In, Bit>,
    /// While idle: write `load_data` to register `load_addr`.
    pub load: Signal<In, Bit>,
    /// Register to load.
    pub load_addr: Signal<In, Bits<6>>,
    /// Value to load (two's complement).
    pub load_data: Signal<In, Bits<128>>,
    /// While idle: the register `read_data` shows on the next clock.
    pub read_addr: Signal<In, Bits<6>>,
    /// The register read.
    pub read_data: Signal<Out, Bits<128>>,
    /// While idle: add `add_data` to register `add_addr` over its low 48 bits, sign-extended
    /// ([`crate::polish::program::add_port`]; read on this clock, written on the next; no
    /// two adds to one register on consecutive clocks, no `load` on the clock after an add,
    /// no add with `go`). The pass accumulates its sums so, straight into the solve's inputs.
    pub add: Signal<In, Bit>,
    /// Register to add to.
    pub add_addr: Signal<In, Bits<6>>,
    /// Value to add (48-bit two's complement).
    pub add_data: Signal<In, Bits<48>>,
    /// While idle: run the program whose first instruction is at `entry`.
    pub go: Signal<In, Bit>,
    /// The program `go` starts ([`crate::polish::program::Rom::entry`]).
    pub entry: Signal<In, Bits<9>>,
    /// Running.
    pub busy: Signal<Out, Bit>,
    /// The last run stopped at a `StopBelow` (until the next `go`).
    pub failed: Signal<Out, Bit>,
    state: DFF<ProgramState>,
    ret: DFF<ProgramState>,
    pc: DFF<Bits<9>>,
    ins: DFF<Bits<30>>,
    x: DFF<Bits<128>>,
    y: DFF<Bits<128>>,
    acc: DFF<Bits<128>>,
    car: DFF<Bits<3>>,
    sign: DFF<Bit>,
    sa: DFF<Bits<2>>,
    sb: DFF<Bits<2>>,
    ia: DFF<Bit>,
    ib: DFF<Bit>,
    ci: DFF<Bit>,
    mdone: DFF<Bit>,
    rem: DFF<Bits<65>>,
    lo: DFF<Bits<33>>,
    lo_c: DFF<Bit>,
    neg: DFF<Bit>,
    cnt: DFF<Bits<8>>,
    fail: DFF<Bit>,
    pend: DFF<Bit>,
    pend_addr: DFF<Bits<6>>,
    add_v: DFF<Bits<48>>,
    rf: RAM<Bits<128>, 6>,
    prog: SyncROM<Bits<30>, 9>,
    kind: Signal<Local, Bits<4>>,
    opb: Signal<Local, Bits<128>>,
    // The adder, `alu = (A ^ ia) + (B ^ ib) + ci` in four 32-bit segments, each segment's
    // carry in from `car` (none from the top), its controls in registers: A (`sa`) is x
    // (0), x << 1 (1), acc (2) or 0 (3); B (`sb`) is the second operand (0), x (1) or 0 (2).
    // A state that `issue`s an add sets them from `sel_a` .. `cin`; `Alu` takes its result
    // into `acc`, `Flush` adds the pending carries, then the state goes on to `then`.
    sel_a: Signal<Local, Bits<2>>,
    sel_b: Signal<Local, Bits<2>>,
    inva: Signal<Local, Bit>,
    invb: Signal<Local, Bit>,
    cin: Signal<Local, Bit>,
    issue: Signal<Local, Bit>,
    then: Signal<Local, ProgramState>,
    alu_a: Signal<Local, Bits<128>>,
    alu_b: Signal<Local, Bits<128>>,
    s0: Signal<Local, Bits<33>>,
    s1: Signal<Local, Bits<33>>,
    s2: Signal<Local, Bits<33>>,
    s3: Signal<Local, Bits<33>>,
    sum: Signal<Local, Bits<128>>,
    carries: Signal<Local, Bits<3>>,
    acc_sra: Signal<Local, Bits<128>>,
    acc_sra8: Signal<Local, Bits<128>>,
    // The multiplier (radix 4, Booth): the next clock's multiplier, the bit below it, and
    // their tests.
    ny: Signal<Local, Bits<128>>,
    my: Signal<Local, Bits<128>>,
    myp: Signal<Local, Bit>,
    my_ones: Signal<Local, Bit>,
    my_zeros: Signal<Local, Bit>,
    my_neg: Signal<Local, Bit>,
    // The divider: the shifted remainder, the halves of the trial subtract, a divisor
    // wider than 64 bits.
    rem2: Signal<Local, Bits<65>>,
    not_y_lo: Signal<Local, Bits<33>>,
    not_y_hi: Signal<Local, Bits<32>>,
    div_lo: Signal<Local, Bits<34>>,
    div_hi: Signal<Local, Bits<33>>,
    div_next_sub: Signal<Local, Bits<34>>,
    div_next_keep: Signal<Local, Bits<34>>,
    div_sub: Signal<Local, Bit>,
    wide: Signal<Local, Bit>,
    // The add port's sum.
    add_sum: Signal<Local, Bits<48>>,
}

impl PolishProgram {
    /// The polish's ROM ([`crate::polish::programs::rom`]), the registers cleared.
    pub fn polish() -> Self {
        Self::new(&crate::polish::programs::rom().words())
    }

    /// `words` in ROM ([`crate::polish::program::Rom::words`]), the registers cleared.
    pub fn new(words: &[u32]) -> Self {
        assert!(words.len() <= PROGRAM_WORDS);
        PolishProgram {
            clock: Default::default(),
            reset: Default::default(),
            load: Default::default(),
            load_addr: Default::default(),
            load_data: Default::default(),
            read_addr: Default::default(),
            read_data: Default::default(),
            add: Default::default(),
            add_addr: Default::default(),
            add_data: Default::default(),
            go: Default::default(),
            entry: Default::default(),
            busy: Default::default(),
            failed: Default::default(),
            state: Default::default(),
            ret: Default::default(),
            pc: Default::default(),
            ins: Default::default(),
            x: Default::default(),
            y: Default::default(),
            acc: Default::default(),
            car: Default::default(),
            sign: Default::default(),
            sa: Default::default(),
            sb: Default::default(),
            ia: Default::default(),
            ib: Default::default(),
            ci: Default::default(),
            mdone: Default::default(),
            rem: Default::default(),
            lo: Default::default(),
            lo_c: Default::default(),
            neg: Default::default(),
            cnt: Default::default(),
            fail: Default::default(),
            pend: Default::default(),
            pend_addr: Default::default(),
            add_v: Default::default(),
            rf: RAM::new((0..64u64).map(|a| (Bits::<6>::from(a), Bits::<128>::default())).collect()),
            prog: SyncROM::new(
                words
                    .iter()
                    .enumerate()
                    .map(|(a, &w)| (Bits::<9>::from(a as u64), Bits::<30>::from(w as u64)))
                    .collect(),
            ),
            kind: Default::default(),
            opb: Default::default(),
            sel_a: Default::default(),
            sel_b: Default::default(),
            inva: Default::default(),
            invb: Default::default(),
            cin: Default::default(),
            issue: Default::default(),
            then: Default::default(),
            alu_a: Default::default(),
            alu_b: Default::default(),
            s0: Default::default(),
            s1: Default::default(),
            s2: Default::default(),
            s3: Default::default(),
            sum: Default::default(),
            carries: Default::default(),
            acc_sra: Default::default(),
            acc_sra8: Default::default(),
            ny: Default::default(),
            my: Default::default(),
            myp: Default::default(),
            my_ones: Default::default(),
            my_zeros: Default::default(),
            my_neg: Default::default(),
            rem2: Default::default(),
            not_y_lo: Default::default(),
            not_y_hi: Default::default(),
            div_lo: Default::default(),
            div_hi: Default::default(),
            div_next_sub: Default::default(),
            div_next_keep: Default::default(),
            div_sub: Default::default(),
            wide: Default::default(),
            add_sum: Default::default(),
        }
    }
}
