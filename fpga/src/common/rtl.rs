//! What the rust_hdl RTL (feature `rtl`) shares: sign extension, the post-processing of
//! rust_hdl's Verilog (repeated modules, attributes, waivers) and the pose word; the
//! Verilog of each design is [`super::verilog`]'s.
//!
//! Each RTL block lives beside its model, in the model's folder under the model's name with
//! `_rtl` (`search/neighbour_pipeline.rs` and `search/neighbour_pipeline_rtl.rs`, ...), and
//! agrees with it port for port on every clock (fpga/tests in rust_hdl's simulator,
//! sim/tests under Verilator).

use rust_hdl::prelude::*;

/// Lane counts the neighbour pipeline, and so the board, accepts (its model RAM is banked
/// `P` ways, its tree pads to 16 leaves; 16 lanes use 9 + 3 * 16 = 57 of the XC6SLX45's 58
/// DSP48A1).
pub const BOARD_LANES: [usize; 4] = [2, 4, 8, 16];

/// Sign extension that is correct for every value (rust_hdl 0.46's `signed_bit_cast`
/// recurses forever on the most negative value). `#[hdl_gen]` recognises calls by name
/// prefix, so this emits the same `$signed(x)`, sign-extended by the assignment context.
pub fn signed_bit_cast_safe<const M: usize, const N: usize>(x: Signed<N>) -> Signed<M> {
    assert!(M >= N && M < 64);
    let raw = x.inner().to_u64();
    Signed::<M>::from(((raw << (64 - N)) as i64) >> (64 - N))
}

/// Drop repeated module definitions (a `Wrapper`'s `cores` is emitted once per instance),
/// keeping the first one and any attribute line in front of it.
pub fn dedup_modules(v: &str) -> String {
    let mut seen = std::collections::HashSet::new();
    let mut out: Vec<&str> = Vec::new();
    let mut skipping = false;
    let mut pending_attr: Option<&str> = None;
    for line in v.lines() {
        let t = line.trim_start();
        if !skipping && t.starts_with("(*") && t.ends_with("*)") {
            if let Some(a) = pending_attr.replace(line) {
                out.push(a);
            }
            continue;
        }
        if !skipping && t.starts_with("module ") {
            let name = t[7..].split(|c: char| c == '(' || c.is_whitespace() || c == ';').next().unwrap_or("");
            if !seen.insert(name.to_string()) {
                skipping = true;
                pending_attr = None;
                continue;
            }
        }
        if skipping {
            if t.starts_with("endmodule") {
                skipping = false;
            }
            continue;
        }
        if let Some(a) = pending_attr.take() {
            out.push(a);
        }
        out.push(line);
    }
    out.join("\n") + "\n"
}

/// A pose as the pipelines' 216-bit pose word (the layout of
/// [`crate::common::format::FxPose::pack`] and of the protocol's pose bytes), for driving the RTL.
pub fn pose_word(p: &crate::common::format::FxPose) -> Bits<216> {
    crate::protocol::layout::pose_bytes(p)
        .iter()
        .enumerate()
        .fold(Bits::<216>::default(), |w, (k, &b)| w | (Bits::<216>::from(b as u64) << (8 * k as u64)))
}

/// The pose of a 216-bit pose word ([`pose_word`]'s inverse).
pub fn word_pose(w: Bits<216>) -> crate::common::format::FxPose {
    let bytes: Vec<u8> = (0..27).map(|k| w.get_bits::<8>(8 * k).to_u64() as u8).collect();
    crate::protocol::layout::pose_from_bytes(&bytes)
}

/// The 64 x 128-bit register files marked for distributed RAM: without the attribute Yosys
/// maps one to 4 RAMB16 (rust_hdl emits no attributes).
pub fn distributed_register_files(v: &str) -> String {
    v.replace("    reg[127:0] mem[63:0];", "    (* ram_style = \"distributed\" *) reg[127:0] mem[63:0];")
}

/// The sequencer's particle-RAM write port (`p_we`, `p_waddr`, `p_wdata`) is a probe for the
/// co-simulation of the sequencer alone; the engine leaves it unconnected (Yosys removes
/// it). The pipeline's `cost` (its sum of squared distances) is not the board's cost: the
/// residual stage after it sums the residuals. The residual stage's `nn_s` goes to the
/// polish's pass without its top bit (13 bits hold every signed residual of a found point),
/// and the polish's datapath's `read_data` above the 32 bits its control reads. Their wire declarations get a targeted `UNUSEDSIGNAL` waiver
/// ([`waive_unused_wires`]), nothing else.
pub fn waive_probe_ports(v: &str) -> String {
    waive_unused_wires(
        v,
        &["filter$p_we", "filter$p_waddr", "filter$p_wdata", "nn$cost", "surf$nn_s", "prog$read_data"],
    )
}

/// `v` with an `UNUSEDSIGNAL` waiver around the declaration of each wire named in `names`
/// (instance outputs a design leaves unconnected on purpose), nothing else.
pub fn waive_unused_wires(v: &str, names: &[&str]) -> String {
    let mut out = String::with_capacity(v.len() + 256);
    for line in v.lines() {
        let t = line.trim_start();
        let unused = t.starts_with("wire") && names.iter().any(|n| t.ends_with(&format!("{n};")));
        if unused {
            out.push_str("/* verilator lint_off UNUSEDSIGNAL */\n");
            out.push_str(line);
            out.push_str("\n/* verilator lint_on UNUSEDSIGNAL */\n");
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// One part of a kernel written as several `#[hdl_gen]` functions (`N` numbers the parts in
/// order). `#[hdl_gen]` turns one function into a block's `always` and takes no calls to
/// helper functions, so a state machine longer than a file is written in parts: the
/// block's `Logic` runs the parts' `update`s one after the other and joins their Verilog in
/// the same order ([`joined_kernel`]), which is the Verilog of the same statements written
/// in one function, byte for byte (the engine's and the sequencer's kernels: the children's
/// wiring and defaults, then the states' arms).
pub trait KernelPart<const N: usize> {
    /// The part's statements (`#[hdl_gen]`'s function).
    fn update(&mut self);
    /// The signals the part drives (written by `#[hdl_gen]`).
    fn connect(&mut self);
    /// The part's Verilog statements (written by `#[hdl_gen]`).
    fn hdl(&self) -> Verilog;
}

/// The Verilog of a kernel's parts, their statements in order in one `always` block.
pub fn joined_kernel(parts: impl IntoIterator<Item = Verilog>) -> Verilog {
    let mut statements: ast::VerilogBlock = Vec::new();
    for part in parts {
        match part {
            Verilog::Combinatorial(block) => statements.extend(block),
            _ => unreachable!("#[hdl_gen] writes a combinatorial block"),
        }
    }
    Verilog::Combinatorial(statements)
}

/// `Logic` for a block whose kernel is written in two parts, [`KernelPart`] 0 then 1:
/// `logic_in_two_parts!([const P: usize] CommandEngine<P>)`, `logic_in_two_parts!([] PfSequencer)`.
macro_rules! logic_in_two_parts {
    ([$($generics:tt)*] $block:ty) => {
        impl<$($generics)*> rust_hdl::prelude::Logic for $block {
            fn update(&mut self) {
                <Self as $crate::common::rtl::KernelPart<0>>::update(self);
                <Self as $crate::common::rtl::KernelPart<1>>::update(self);
            }

            fn connect(&mut self) {
                <Self as $crate::common::rtl::KernelPart<0>>::connect(self);
                <Self as $crate::common::rtl::KernelPart<1>>::connect(self);
            }

            fn hdl(&self) -> rust_hdl::prelude::Verilog {
                $crate::common::rtl::joined_kernel([
                    <Self as $crate::common::rtl::KernelPart<0>>::hdl(self),
                    <Self as $crate::common::rtl::KernelPart<1>>::hdl(self),
                ])
            }
        }
    };
}
pub(crate) use logic_in_two_parts;
