//! `Mul18`: a registered 18 x 18 signed multiplier (`p <= a * b` on the rising edge, 36-bit
//! product), one DSP48A1 on the Spartan-6.
//!
//! rust_hdl's `*` only multiplies 16 x 16, so this block is a Verilog [`Wrapper`]: each
//! instance's module instantiates [`MUL18_MODULE`], a real (synthesisable, simulatable)
//! implementation that Yosys maps onto a DSP48A1 and Verilator runs as is. rust_hdl emits
//! the `cores` text once per instance; [`super::dedup_modules`] keeps only the first copy.
//! The Rust `update()` is the simulation model of the same register.

use rust_hdl::prelude::*;

/// Name of the Verilog module that implements the multiplier.
pub const MUL18_MODULE: &str = "pficp_smul18x18";

/// The Verilog implementation of [`MUL18_MODULE`].
pub const MUL18_VERILOG: &str = "\
module pficp_smul18x18(input wire clk, input wire signed [17:0] a, input wire signed [17:0] b,
                       output reg signed [35:0] p);
  always @(posedge clk) p <= $signed(a) * $signed(b);
endmodule
";

/// Registered 18 x 18 -> 36 signed multiplier (latency 1).
#[derive(LogicBlock, Default)]
pub struct Mul18 {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Multiplicand.
    pub a: Signal<In, Signed<18>>,
    /// Multiplier.
    pub b: Signal<In, Signed<18>>,
    /// `a * b` as sampled at the previous rising edge.
    pub p: Signal<Out, Signed<36>>,
}

impl Logic for Mul18 {
    fn update(&mut self) {
        if self.clock.pos_edge() {
            self.p.next = Signed::<36>::from(self.a.val().bigint() * self.b.val().bigint());
        }
    }

    fn connect(&mut self) {
        self.p.connect();
    }

    fn hdl(&self) -> Verilog {
        Verilog::Wrapper(Wrapper {
            code: format!("{MUL18_MODULE} u_mul(.clk(clock), .a(a), .b(b), .p(p));"),
            cores: MUL18_VERILOG.into(),
        })
    }
}
