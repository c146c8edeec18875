//! The neighbour pipeline's lanes (docs/pipeline.md, "The neighbour pipeline"; model
//! [`crate::search::neighbour_pipeline::NeighbourPipelineModel`]): [`NeighbourLane`] (A, squares in
//! DSP48A1s) and [`NeighbourLaneB`] (B, squares from block-RAM tables, [`SquareRom`]), both
//! behind the same [`LaneFront`]: lane `b` of `P` owns the stored points at addresses
//! `≡ b (mod P)` in its bank of the model RAM ([`BankRam`]); for a chunk starting at `addr` it
//! reads the one of them among `addr .. addr + P`, bank row `(addr >> log2 P) + (b < addr mod
//! P)`, valid if that address is below the range's end (`span = end - addr` ahead). Then
//! the distance pipeline against the chunk's query (s1 differences, s2 squares, s3
//! `dx^2 + dy^2` and `dz^2`, s4 the sum), and the clamp: the registered key
//! `d2 << 12 | index`, or the neutral `CAP_D2 << 12` if the lane has no candidate or
//! `d2 >= CAP_D2`.

use crate::common::rtl::signed_bit_cast_safe;
use crate::search::grid::CAP_D2;
use crate::search::mul18_rtl::Mul18;
use rust_hdl::prelude::*;
use std::collections::BTreeMap;

/// A bank of the model RAM: `4096 / P` words of 48 bits, word `a >> lsb` for a 12-bit
/// address `a` (synchronous read, read-first, one write port). A Verilog block of its own
/// because its depth depends on `P` at run time.
#[derive(LogicBlock, Default)]
pub struct BankRam {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Read address (bits `11..lsb` select the word).
    pub read_address: Signal<In, Bits<12>>,
    /// The word read at the last edge.
    pub read_data: Signal<Out, Bits<48>>,
    /// Write `write_data` at this edge.
    pub write_enable: Signal<In, Bit>,
    /// Write address (bits `11..lsb`).
    pub write_address: Signal<In, Bits<12>>,
    /// The word written.
    pub write_data: Signal<In, Bits<48>>,
    _lsb: usize,
    _sim: BTreeMap<u64, Bits<48>>,
}

impl BankRam {
    /// A bank addressed by bits `11..lsb`.
    pub fn new(lsb: usize) -> BankRam {
        assert!(lsb < 12);
        BankRam { _lsb: lsb, ..Default::default() }
    }
}

impl Logic for BankRam {
    fn update(&mut self) {
        if self.clock.pos_edge() {
            let r = self.read_address.val().to_u64() >> self._lsb;
            self.read_data.next = *self._sim.get(&r).unwrap_or(&Bits::<48>::default());
            if self.write_enable.val() {
                self._sim.insert(self.write_address.val().to_u64() >> self._lsb, self.write_data.val());
            }
        }
    }

    fn connect(&mut self) {
        self.read_data.connect();
    }

    fn hdl(&self) -> Verilog {
        let words = 1usize << (12 - self._lsb);
        let unused = if self._lsb == 0 {
            String::new()
        } else {
            // The low address bits select the bank, outside.
            format!(
                "/* verilator lint_off UNUSEDSIGNAL */\nwire [{l}:0] unused_low = read_address[{l}:0] ^ write_address[{l}:0];\n\
                 /* verilator lint_on UNUSEDSIGNAL */\n",
                l = self._lsb - 1
            )
        };
        Verilog::Custom(format!(
            "\
reg [47:0] mem[{last}:0];
{unused}
always @(posedge clock) begin
   read_data <= mem[read_address[11:{lsb}]];
   if (write_enable) begin
      mem[write_address[11:{lsb}]] <= write_data;
   end
end
",
            last = words - 1,
            lsb = self._lsb,
        ))
    }
}

/// The front end both kinds of lane share (lane `id` of `P`): its bank of the model RAM
/// ([`BankRam`], written with the addresses `≡ id (mod P)`) and the issue. For a chunk
/// starting at `addr` the lane's address `addr + ((id - addr) mod P)` is its bank row
/// (`addr >> log2 P`, plus one if `id < addr mod P`) and the candidate's index; the lane
/// holds a candidate if that address is below the range's end (`span = end - addr` ahead).
/// Registered with the bank's read (c0): `valid`, `index` and `point`, one edge after the
/// issue.
#[derive(LogicBlock)]
pub struct LaneFront {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// A chunk of a range is issued at this edge (not a marker).
    pub issue: Signal<In, Bit>,
    /// The chunk's first address.
    pub addr: Signal<In, Bits<13>>,
    /// The range's end less `addr` (14 bits; at least 1 when `issue`).
    pub span: Signal<In, Bits<14>>,
    /// Model RAM write port.
    pub model_we: Signal<In, Bit>,
    /// Model write address.
    pub model_waddr: Signal<In, Bits<12>>,
    /// Model write data.
    pub model_wdata: Signal<In, Bits<48>>,
    /// The lane holds a candidate (one edge after the issue).
    pub valid: Signal<Out, Bit>,
    /// The candidate's index (its address).
    pub index: Signal<Out, Bits<12>>,
    /// The candidate's stored point (x | y | z, Q3.13).
    pub point: Signal<Out, Bits<48>>,
    id: Constant<Bits<12>>,
    pmask: Constant<Bits<12>>,
    pc: Constant<Bits<14>>,
    bank: BankRam,
    v0: DFF<Bit>,
    i0: DFF<Bits<12>>,
    off: Signal<Local, Bits<12>>,
    rel: Signal<Local, Bits<12>>,
    idx: Signal<Local, Bits<12>>,
}

impl LaneFront {
    /// Lane `id` of `lanes` (a power of two, 2 to 16).
    pub fn new(id: usize, lanes: usize) -> LaneFront {
        assert!(lanes.is_power_of_two() && (2..=16).contains(&lanes) && id < lanes);
        LaneFront {
            clock: Default::default(),
            issue: Default::default(),
            addr: Default::default(),
            span: Default::default(),
            model_we: Default::default(),
            model_waddr: Default::default(),
            model_wdata: Default::default(),
            valid: Default::default(),
            index: Default::default(),
            point: Default::default(),
            id: Constant::new((id as u64).into()),
            pmask: Constant::new(((lanes - 1) as u64).into()),
            pc: Constant::new((lanes as u64).into()),
            bank: BankRam::new(lanes.trailing_zeros() as usize),
            v0: Default::default(),
            i0: Default::default(),
            off: Default::default(),
            rel: Default::default(),
            idx: Default::default(),
        }
    }
}

impl Logic for LaneFront {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, v0, i0);
        self.bank.clock.next = self.clock.val();
        self.off.next = bit_cast::<12, 13>(self.addr.val()) & self.pmask.val();
        self.rel.next = (self.id.val() - self.off.val()) & self.pmask.val();
        if self.id.val() < self.off.val() {
            self.idx.next = (bit_cast::<12, 13>(self.addr.val()) & !self.pmask.val())
                + self.pc.val().get_bits::<12>(0)
                + self.id.val();
        } else {
            self.idx.next = (bit_cast::<12, 13>(self.addr.val()) & !self.pmask.val()) + self.id.val();
        }
        self.bank.read_address.next = self.idx.val();
        self.bank.write_enable.next =
            self.model_we.val() && ((self.model_waddr.val() & self.pmask.val()) == self.id.val());
        self.bank.write_address.next = self.model_waddr.val();
        self.bank.write_data.next = self.model_wdata.val();
        self.v0.d.next = self.issue.val()
            && ((self.span.val() >= self.pc.val()) || (bit_cast::<14, 12>(self.rel.val()) < self.span.val()));
        self.i0.d.next = self.idx.val();
        self.valid.next = self.v0.q.val();
        self.index.next = self.i0.q.val();
        self.point.next = self.bank.read_data.val();
    }
}

/// One lane (number `id` of `P`) with its front end ([`LaneFront`]).
#[derive(LogicBlock)]
pub struct NeighbourLane {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// A chunk of a range is issued at this edge (not a marker).
    pub issue: Signal<In, Bit>,
    /// The chunk's first address.
    pub addr: Signal<In, Bits<13>>,
    /// The range's end less `addr` (14 bits; at least 1 when `issue`).
    pub span: Signal<In, Bits<14>>,
    /// The chunk's query point (the top's chunk register, one edge after the issue).
    pub q: Signal<In, Bits<48>>,
    /// Model RAM write port (the lane's bank takes the addresses `≡ id (mod P)`).
    pub model_we: Signal<In, Bit>,
    /// Model write address.
    pub model_waddr: Signal<In, Bits<12>>,
    /// Model write data.
    pub model_wdata: Signal<In, Bits<48>>,
    /// The clamped key `d2 << 12 | index` (or `CAP_D2 << 12`), five edges after the issue.
    pub key: Signal<Out, Bits<33>>,
    cap_key: Constant<Bits<33>>,
    front: LaneFront,
    d1: [DFF<Signed<17>>; 3],
    d1b: [DFF<Signed<17>>; 3],
    v1: DFF<Bit>,
    i1: DFF<Bits<12>>,
    mul: [Mul18; 3],
    v2: DFF<Bit>,
    i2: DFF<Bits<12>>,
    s3a: DFF<Bits<34>>,
    s3b: DFF<Bits<34>>,
    v3: DFF<Bit>,
    i3: DFF<Bits<12>>,
    s4: DFF<Bits<34>>,
    v4: DFF<Bit>,
    i4: DFF<Bits<12>>,
    key_r: DFF<Bits<33>>,
    mq: [Signal<Local, Signed<16>>; 3],
    qq: [Signal<Local, Signed<16>>; 3],
    sq: [Signal<Local, Bits<36>>; 3],
}

impl NeighbourLane {
    /// Lane `id` of `lanes` (a power of two, 2 to 16).
    pub fn new(id: usize, lanes: usize) -> NeighbourLane {
        assert!(lanes.is_power_of_two() && (2..=16).contains(&lanes) && id < lanes);
        NeighbourLane {
            clock: Default::default(),
            issue: Default::default(),
            addr: Default::default(),
            span: Default::default(),
            q: Default::default(),
            model_we: Default::default(),
            model_waddr: Default::default(),
            model_wdata: Default::default(),
            key: Default::default(),
            cap_key: Constant::new((CAP_D2 << 12).into()),
            front: LaneFront::new(id, lanes),
            d1: Default::default(),
            d1b: Default::default(),
            v1: Default::default(),
            i1: Default::default(),
            mul: Default::default(),
            v2: Default::default(),
            i2: Default::default(),
            s3a: Default::default(),
            s3b: Default::default(),
            v3: Default::default(),
            i3: Default::default(),
            s4: Default::default(),
            v4: Default::default(),
            i4: Default::default(),
            key_r: Default::default(),
            mq: Default::default(),
            qq: Default::default(),
            sq: Default::default(),
        }
    }
}

impl Logic for NeighbourLane {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, v1, i1, v2, i2, s3a, s3b, v3, i3, s4, v4, i4, key_r);
        for k in 0..3 {
            self.d1[k].clock.next = self.clock.val();
            self.d1b[k].clock.next = self.clock.val();
            self.d1b[k].d.next = self.d1b[k].q.val();
            self.mul[k].clock.next = self.clock.val();
        }
        // Issue, bank and c0: the front end.
        self.front.clock.next = self.clock.val();
        self.front.issue.next = self.issue.val();
        self.front.addr.next = self.addr.val();
        self.front.span.next = self.span.val();
        self.front.model_we.next = self.model_we.val();
        self.front.model_waddr.next = self.model_waddr.val();
        self.front.model_wdata.next = self.model_wdata.val();
        // s1: differences (17-bit), twice: with A and B from one register, Yosys 0.23 packs
        // the subtraction into the DSP48A1 pre-adder of B and leaves A undriven (a wrong
        // netlist); two registers both go into the DSP (A1REG, B1REG), the pre-adder unused.
        for k in 0..3 {
            self.mq[k].next = signed_cast(self.front.point.val().get_bits::<16>(16 * k));
            self.qq[k].next = signed_cast(self.q.val().get_bits::<16>(16 * k));
            self.d1[k].d.next = signed_bit_cast_safe(self.qq[k].val()) - signed_bit_cast_safe(self.mq[k].val());
            if self.front.valid.val() {
                self.d1b[k].d.next = signed_bit_cast_safe(self.qq[k].val()) - signed_bit_cast_safe(self.mq[k].val());
            }
        }
        self.v1.d.next = self.front.valid.val();
        self.i1.d.next = self.front.index.val();
        // s2: squares.
        for k in 0..3 {
            self.mul[k].a.next = signed_bit_cast_safe(self.d1[k].q.val());
            self.mul[k].b.next = signed_bit_cast_safe(self.d1b[k].q.val());
            self.sq[k].next = unsigned_cast(self.mul[k].p.val());
        }
        self.v2.d.next = self.v1.q.val();
        self.i2.d.next = self.i1.q.val();
        // s3, s4: the sum.
        self.s3a.d.next = bit_cast::<34, 36>(self.sq[0].val()) + bit_cast::<34, 36>(self.sq[1].val());
        self.s3b.d.next = bit_cast::<34, 36>(self.sq[2].val());
        self.v3.d.next = self.v2.q.val();
        self.i3.d.next = self.i2.q.val();
        self.s4.d.next = self.s3a.q.val() + self.s3b.q.val();
        self.v4.d.next = self.v3.q.val();
        self.i4.d.next = self.i3.q.val();
        // Clamp: `d2 < CAP_D2 = 2^20` iff bits 33..20 are zero.
        if self.v4.q.val() && (self.s4.q.val().get_bits::<14>(20) == 0) {
            self.key_r.d.next = (bit_cast::<33, 34>(self.s4.q.val()) << 12) | bit_cast::<33, 12>(self.i4.q.val());
        } else {
            self.key_r.d.next = self.cap_key.val();
        }
        self.key.next = self.key_r.q.val();
    }
}

/// A table of squares for the B lanes: word `y` (9 bits) holds `y^2 >> 2` (16 bits; the
/// square's two low bits are `0 | (y & 1)`), read through `N` ports (1 or 2), each
/// registered (one edge, like a block RAM's output register): 512 x 16 bits, one RAMB8 with
/// one or both of its ports.
#[derive(LogicBlock)]
pub struct SquareRom<const N: usize> {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// The ports' addresses.
    pub addr: [Signal<In, Bits<9>>; N],
    /// `addr^2 >> 2` at the last edge, each port.
    pub data: [Signal<Out, Bits<16>>; N],
}

impl<const N: usize> Default for SquareRom<N> {
    fn default() -> Self {
        SquareRom {
            clock: Default::default(),
            addr: std::array::from_fn(|_| Default::default()),
            data: std::array::from_fn(|_| Default::default()),
        }
    }
}

/// `y^2 >> 2` for a 9-bit `y`.
fn quarter_square(y: Bits<9>) -> Bits<16> {
    let y = y.to_u64();
    ((y * y) >> 2).into()
}

impl<const N: usize> Logic for SquareRom<N> {
    fn update(&mut self) {
        if self.clock.pos_edge() {
            for k in 0..N {
                self.data[k].next = quarter_square(self.addr[k].val());
            }
        }
    }

    fn connect(&mut self) {
        for k in 0..N {
            self.data[k].connect();
        }
    }

    fn hdl(&self) -> Verilog {
        assert!((1..=2).contains(&N), "a block RAM has two ports");
        let reads: String = (0..N).map(|k| format!("   data${k} <= mem[addr${k}];\n")).collect();
        Verilog::Custom(format!(
            "\
reg [15:0] mem[511:0];
integer i;
/* verilator lint_off UNUSEDSIGNAL */
reg [17:0] sq;
/* verilator lint_on UNUSEDSIGNAL */
initial begin
   for (i = 0; i < 512; i = i + 1) begin
      sq = i[8:0] * i[8:0];
      mem[i] = sq[17:2];
   end
end
always @(posedge clock) begin
{reads}end
"
        ))
    }
}

/// One B lane (number `id` of `P`), its [`LaneFront`]'s bank a bank of the model RAM's
/// second copy: the A lane's front end and key, without DSP48A1s. A difference of `2^10`
/// (`h`) or more along any axis makes the lane's key the capped one (its distance is at least
/// `CAP_D2`), so the lane squares 10-bit magnitudes `x = 512 t + y` only:
/// `x^2 = y^2 + t (256 + y) 2^10`, `y^2` from block-RAM tables of `y^2 >> 2`
/// ([`SquareRom`]: `dx` and `dy` through both ports of one, `dz` through another; two RAMB8
/// a lane) and the rest a shift. Stages: s1 `q - m` and `m - q`; s2 the tables' words
/// (addressed by the magnitudes' low 9 bits), the magnitudes' low bits, the sum of the
/// three `t (256 + y) 2^10` and a flag for a magnitude of `2^10` or more; s3
/// `dx^2 + dy^2` and `dz^2` with that sum; s4 the sum; then the clamp, as the A lane.
#[derive(LogicBlock)]
pub struct NeighbourLaneB {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// A chunk of a range is issued to the B lanes at this edge.
    pub issue: Signal<In, Bit>,
    /// The chunk's first address.
    pub addr: Signal<In, Bits<13>>,
    /// The range's end less `addr` (14 bits; at least 1 when `issue`).
    pub span: Signal<In, Bits<14>>,
    /// The chunk's query point (the top's chunk register, one edge after the issue).
    pub q: Signal<In, Bits<48>>,
    /// Model RAM write port (the lane's bank takes the addresses `≡ id (mod P)`).
    pub model_we: Signal<In, Bit>,
    /// Model write address.
    pub model_waddr: Signal<In, Bits<12>>,
    /// Model write data.
    pub model_wdata: Signal<In, Bits<48>>,
    /// The clamped key `d2 << 12 | index` (or `CAP_D2 << 12`), five edges after the issue.
    pub key: Signal<Out, Bits<33>>,
    cap_key: Constant<Bits<33>>,
    front: LaneFront,
    c18: Constant<Bits<22>>,
    rom_xy: SquareRom<2>,
    rom_z: SquareRom<1>,
    dp: [DFF<Signed<17>>; 3],
    dn: [DFF<Signed<17>>; 3],
    v1: DFF<Bit>,
    i1: DFF<Bits<12>>,
    far2: DFF<Bit>,
    lsb2: [DFF<Bit>; 3],
    hi2: DFF<Bits<22>>,
    v2: DFF<Bit>,
    i2: DFF<Bits<12>>,
    s3a: DFF<Bits<19>>,
    s3b: DFF<Bits<22>>,
    far3: DFF<Bit>,
    v3: DFF<Bit>,
    i3: DFF<Bits<12>>,
    s4: DFF<Bits<23>>,
    far4: DFF<Bit>,
    v4: DFF<Bit>,
    i4: DFF<Bits<12>>,
    key_r: DFF<Bits<33>>,
    mq: [Signal<Local, Signed<16>>; 3],
    qq: [Signal<Local, Signed<16>>; 3],
    mag: [Signal<Local, Bits<17>>; 3],
    hi: [Signal<Local, Bits<22>>; 3],
    far: Signal<Local, Bit>,
    sq: [Signal<Local, Bits<18>>; 3],
}

impl NeighbourLaneB {
    /// B lane `id` of `lanes` (a power of two, 2 to 16).
    pub fn new(id: usize, lanes: usize) -> NeighbourLaneB {
        assert!(lanes.is_power_of_two() && (2..=16).contains(&lanes) && id < lanes);
        NeighbourLaneB {
            clock: Default::default(),
            issue: Default::default(),
            addr: Default::default(),
            span: Default::default(),
            q: Default::default(),
            model_we: Default::default(),
            model_waddr: Default::default(),
            model_wdata: Default::default(),
            key: Default::default(),
            cap_key: Constant::new((CAP_D2 << 12).into()),
            front: LaneFront::new(id, lanes),
            c18: Constant::new((1u64 << 18).into()),
            rom_xy: Default::default(),
            rom_z: Default::default(),
            dp: Default::default(),
            dn: Default::default(),
            v1: Default::default(),
            i1: Default::default(),
            far2: Default::default(),
            lsb2: Default::default(),
            hi2: Default::default(),
            v2: Default::default(),
            i2: Default::default(),
            s3a: Default::default(),
            s3b: Default::default(),
            far3: Default::default(),
            v3: Default::default(),
            i3: Default::default(),
            s4: Default::default(),
            far4: Default::default(),
            v4: Default::default(),
            i4: Default::default(),
            key_r: Default::default(),
            mq: Default::default(),
            qq: Default::default(),
            mag: Default::default(),
            hi: Default::default(),
            far: Default::default(),
            sq: Default::default(),
        }
    }
}

impl Logic for NeighbourLaneB {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, v1, i1, far2, hi2, v2, i2, s3a, s3b, far3, v3, i3, s4, far4, v4, i4, key_r);
        self.rom_xy.clock.next = self.clock.val();
        self.rom_z.clock.next = self.clock.val();
        for k in 0..3 {
            self.dp[k].clock.next = self.clock.val();
            self.dp[k].d.next = self.dp[k].q.val();
            self.dn[k].clock.next = self.clock.val();
            self.dn[k].d.next = self.dn[k].q.val();
            self.lsb2[k].clock.next = self.clock.val();
            self.lsb2[k].d.next = self.lsb2[k].q.val();
        }
        // Issue, bank and c0: the front end.
        self.front.clock.next = self.clock.val();
        self.front.issue.next = self.issue.val();
        self.front.addr.next = self.addr.val();
        self.front.span.next = self.span.val();
        self.front.model_we.next = self.model_we.val();
        self.front.model_waddr.next = self.model_waddr.val();
        self.front.model_wdata.next = self.model_wdata.val();
        // s1: the differences both ways (17-bit), so that the magnitude is a choice.
        for k in 0..3 {
            self.mq[k].next = signed_cast(self.front.point.val().get_bits::<16>(16 * k));
            self.qq[k].next = signed_cast(self.q.val().get_bits::<16>(16 * k));
            self.dp[k].d.next = signed_bit_cast_safe(self.qq[k].val()) - signed_bit_cast_safe(self.mq[k].val());
            self.dn[k].d.next = signed_bit_cast_safe(self.mq[k].val()) - signed_bit_cast_safe(self.qq[k].val());
        }
        self.v1.d.next = self.front.valid.val();
        self.i1.d.next = self.front.index.val();
        // s2: magnitude `x = 512 t + y` (`|-2^16|` is bit 16); `y^2 >> 2` from the tables, `y`'s
        // low bit, `t (256 + y) << 10` summed over the axes, a magnitude of 2^10 or more.
        for k in 0..3 {
            self.mag[k].next = unsigned_cast(self.dp[k].q.val());
            if self.mag[k].val().get_bit(16) {
                self.mag[k].next = unsigned_cast(self.dn[k].q.val());
            }
            self.lsb2[k].d.next = self.mag[k].val().get_bit(0);
        }
        // (A loop index inside `bit_cast` does not translate: the axes one by one.)
        self.hi[0].next = (bit_cast::<22, 9>(self.mag[0].val().get_bits::<9>(0)) << 10) + self.c18.val();
        self.hi[1].next = (bit_cast::<22, 9>(self.mag[1].val().get_bits::<9>(0)) << 10) + self.c18.val();
        self.hi[2].next = (bit_cast::<22, 9>(self.mag[2].val().get_bits::<9>(0)) << 10) + self.c18.val();
        for k in 0..3 {
            if !self.mag[k].val().get_bit(9) {
                self.hi[k].next = 0.into();
            }
        }
        self.far.next = (self.mag[0].val().get_bits::<7>(10) != 0)
            || (self.mag[1].val().get_bits::<7>(10) != 0)
            || (self.mag[2].val().get_bits::<7>(10) != 0);
        self.rom_xy.addr[0].next = self.mag[0].val().get_bits::<9>(0);
        self.rom_xy.addr[1].next = self.mag[1].val().get_bits::<9>(0);
        self.rom_z.addr[0].next = self.mag[2].val().get_bits::<9>(0);
        self.hi2.d.next = self.hi[0].val() + self.hi[1].val() + self.hi[2].val();
        self.far2.d.next = self.far.val();
        self.v2.d.next = self.v1.q.val();
        self.i2.d.next = self.i1.q.val();
        // s3, s4: the sum (below 3 * 2^20 unless far).
        self.sq[0].next = bit_cast::<18, 16>(self.rom_xy.data[0].val()) << 2;
        if self.lsb2[0].q.val() {
            self.sq[0].next = (bit_cast::<18, 16>(self.rom_xy.data[0].val()) << 2) + 1;
        }
        self.sq[1].next = bit_cast::<18, 16>(self.rom_xy.data[1].val()) << 2;
        if self.lsb2[1].q.val() {
            self.sq[1].next = (bit_cast::<18, 16>(self.rom_xy.data[1].val()) << 2) + 1;
        }
        self.sq[2].next = bit_cast::<18, 16>(self.rom_z.data[0].val()) << 2;
        if self.lsb2[2].q.val() {
            self.sq[2].next = (bit_cast::<18, 16>(self.rom_z.data[0].val()) << 2) + 1;
        }
        self.s3a.d.next = bit_cast::<19, 18>(self.sq[0].val()) + bit_cast::<19, 18>(self.sq[1].val());
        self.s3b.d.next = bit_cast::<22, 18>(self.sq[2].val()) + self.hi2.q.val();
        self.far3.d.next = self.far2.q.val();
        self.v3.d.next = self.v2.q.val();
        self.i3.d.next = self.i2.q.val();
        self.s4.d.next = bit_cast::<23, 19>(self.s3a.q.val()) + bit_cast::<23, 22>(self.s3b.q.val());
        self.far4.d.next = self.far3.q.val();
        self.v4.d.next = self.v3.q.val();
        self.i4.d.next = self.i3.q.val();
        // Clamp: `d2 < CAP_D2 = 2^20` iff no magnitude reached 2^10 and bits 22..20 are zero.
        if self.v4.q.val() && !self.far4.q.val() && (self.s4.q.val().get_bits::<3>(20) == 0) {
            self.key_r.d.next = (bit_cast::<33, 23>(self.s4.q.val()) << 12) | bit_cast::<33, 12>(self.i4.q.val());
        } else {
            self.key_r.d.next = self.cap_key.val();
        }
        self.key.next = self.key_r.q.val();
    }
}
