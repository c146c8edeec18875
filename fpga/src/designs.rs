//! The one list of generated designs ([`DESIGNS`]): each design's name, its Verilog generator
//! (feature `rtl`), its parameters, and its ports with their widths taken from the formats.
//!
//! Who reads it:
//! - `hdl-gen` (its `--design` values are the entries with a [`Design::cli`] name);
//! - `sim/build.rs`, which verilates every entry (the lane-parametrised ones once a lane
//!   count), checks each Verilated header against [`Design::ports`] and writes the shim's
//!   port copies in their order;
//! - the co-simulation's wrappers (`sim/src/wrappers/`), which name the outputs they compare
//!   from the same ports ([`outputs`], [`output_words`]).
//!
//! Adding a design is one entry here (and its wrapper in `sim/src/wrappers/`). The ports are
//! declared in the RTL structs (the `*_rtl.rs` files); Verilator's header is checked against this
//! list on every co-simulation build, so a width here that disagrees with the RTL fails that
//! build.

use crate::board::BoardConfig;
use crate::common::format::{COST_BITS, DIST_BITS, INDEX_BITS, MAX_PARTICLES, MAX_POINTS, POINT_WORD_BITS, POSE_BITS};

/// A port: its name, direction and width. `clock` is driven by the co-simulation's `tick`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Port {
    /// The Verilog port name.
    pub name: &'static str,
    /// An input (else an output).
    pub input: bool,
    /// Bits.
    pub width: usize,
}

const fn i(name: &'static str, width: u32) -> Port {
    Port { name, input: true, width: width as usize }
}

const fn o(name: &'static str, width: u32) -> Port {
    Port { name, input: false, width: width as usize }
}

/// Bits of an address over `n` entries (`ceil(log2 n)`).
const fn addr_bits(n: usize) -> u32 {
    usize::BITS - (n - 1).leading_zeros()
}

/// Bits of a count `0..=n`.
const fn count_bits(n: usize) -> u32 {
    usize::BITS - n.leading_zeros()
}

// The widths the ports share, from the formats.

/// A pose word: the 9 matrix entries and 3 translations of [`crate::common::format::FxPose::pack`].
const POSE_WORD_BITS: u32 = 12 * POSE_BITS;
/// A translation as [`crate::common::format::pack_translation`] packs it.
const TRANSLATION_BITS: u32 = 3 * POSE_BITS;
/// The grid's cell table: an address over its entries, and a point index `0..=MAX_POINTS`.
const TABLE_ADDR_BITS: u32 = addr_bits(crate::protocol::messages::TABLE_ENTRIES);
const TABLE_DATA_BITS: u32 = count_bits(MAX_POINTS);
/// The weight stage: its right shift of the cost excess, its multiplier, a weight (Q0.16,
/// [`crate::protocol::messages::WEIGHT_BYTES`]) and their sum ([`crate::protocol::messages::W_SUM_MASK`]).
const PRE_SHIFT_BITS: u32 = 6;
const Q_MUL_BITS: u32 = 17;
const WEIGHT_BITS: u32 = 8 * crate::protocol::messages::WEIGHT_BYTES as u32;
const W_SUM_BITS: u32 = crate::protocol::messages::W_SUM_MASK.count_ones();
/// The residual stage's signed residual before squaring (two's complement).
const SIGNED_RESIDUAL_BITS: u32 = 14;
/// The sequencer's multiplier (the one DSP48A1 the polish borrows): multiplicand (a filter
/// register, [`crate::filter::pf::REG_BITS`]), multiplier, product.
const MUL_A_BITS: u32 = crate::filter::pf::REG_BITS;
const MUL_B_BITS: u32 = 18;
const MUL_PRODUCT_BITS: u32 = MUL_A_BITS + MUL_B_BITS;
/// The sequencer's particle RAM address `{half, particle, parameter}`.
const PARTICLE_ADDR_BITS: u32 = 1 + addr_bits(MAX_PARTICLES) + addr_bits(crate::filter::pf::PARAMS);
/// The iterations the sequencer counts.
const ITERATION_BITS: u32 = 16;
/// The polish's datapath: a register address, a program address.
const REGISTER_ADDR_BITS: u32 = addr_bits(crate::polish::program::REGISTERS);
const ENTRY_BITS: u32 = addr_bits(crate::polish::program::PROGRAM_WORDS);
/// The polish's pass: its gate (`s^2 <= tau2`) and a point's signed residual.
const TAU2_BITS: u32 = 32;
const PASS_RESIDUAL_BITS: u32 = 13;
/// Starts, steps and start indices of the polish.
const STARTS_BITS: u32 = crate::protocol::run_request::STARTS_BITS;
/// The board's LEDs.
const LED_BITS: u32 = 4;

/// What a design's Verilog depends on.
#[derive(Clone, Copy, Debug)]
pub enum Params {
    /// Nothing: one Verilog.
    None,
    /// The lane count `P` of the neighbour pipeline (one of `rtl::BOARD_LANES`): the
    /// co-simulation verilates it once a lane count.
    Lanes,
    /// A board configuration (lanes, clock, baud); the co-simulation verilates it with this
    /// one.
    Board(fn() -> BoardConfig),
}

/// One generated design.
#[derive(Clone, Copy, Debug)]
pub struct Design {
    /// The design's name: the co-simulation's key (`verilated_models`) and its Verilog file's
    /// stem.
    pub name: &'static str,
    /// Its `hdl-gen --design` value, if `hdl-gen` writes it.
    pub cli: Option<&'static str>,
    /// What it is (`hdl-gen --help`).
    pub about: &'static str,
    /// The Verilator prefix of its co-simulation model; the lane count is appended for a
    /// [`Params::Lanes`] design.
    pub prefix: &'static str,
    /// What its Verilog depends on.
    pub params: Params,
    /// The generator's path, as `hdl-gen` reports where the Verilog came from.
    pub generator: &'static str,
    /// The Verilog (top module `top`) for a configuration (its `lanes` for a
    /// [`Params::Lanes`] design; ignored by a [`Params::None`] design).
    #[cfg(feature = "rtl")]
    pub verilog: fn(&BoardConfig) -> String,
    /// The ports, in the order of the packed input and output arrays of the co-simulation.
    pub ports: &'static [Port],
    /// Where the ports are declared and documented.
    pub spec: &'static str,
}

impl Design {
    /// Where the Verilog for `config` came from, as `hdl-gen` reports it.
    pub fn source(&self, config: &BoardConfig) -> String {
        match self.params {
            Params::None => format!("{}()", self.generator),
            Params::Lanes => format!("{}({})", self.generator, config.lanes),
            Params::Board(_) => format!(
                "{}(BoardConfig {{ lanes: {}, clock_hz: {}, baud: {} }})",
                self.generator, config.lanes, config.clock_hz, config.baud
            ),
        }
    }

    /// The design with `hdl-gen --design` value `cli`.
    pub fn by_cli(cli: &str) -> Option<&'static Design> {
        DESIGNS.iter().find(|d| d.cli == Some(cli))
    }
}

/// The neighbour pipeline (`NeighbourPipeline<P>`, docs/pipeline.md "The neighbour pipeline";
/// its model's ports [`crate::search::neighbour_pipeline::GridInputs`], [`crate::search::pipeline::Outputs`]).
pub const NEIGHBOUR_PIPELINE: Design = Design {
    name: "neighbour_pipeline",
    cli: Some("neighbour-pipeline"),
    about: "`NeighbourPipeline`: lanes over one scan point's candidates in its 27 cells (the board's search)",
    prefix: "Vnbr",
    params: Params::Lanes,
    generator: "pficp_fpga::common::verilog::neighbour_pipeline_verilog",
    #[cfg(feature = "rtl")]
    verilog: |c| crate::common::verilog::neighbour_pipeline_verilog(c.lanes),
    ports: &[
        i("clock", 1),
        i("model_we", 1),
        i("model_waddr", INDEX_BITS),
        i("model_wdata", POINT_WORD_BITS),
        i("table_we", 1),
        i("table_waddr", TABLE_ADDR_BITS),
        i("table_wdata", TABLE_DATA_BITS),
        i("start", 1),
        i("pose", POSE_WORD_BITS),
        i("scan_valid", 1),
        i("scan_data", POINT_WORD_BITS),
        i("scan_last", 1),
        o("scan_ready", 1),
        o("busy", 1),
        o("nn_valid", 1),
        o("nn_index", INDEX_BITS),
        o("nn_dist", DIST_BITS),
        o("cost_valid", 1),
        o("cost", COST_BITS),
        o("nn_point", POINT_WORD_BITS),
    ],
    spec: "docs/pipeline.md, the neighbour pipeline (fpga/src/search/neighbour_pipeline_rtl.rs)",
};

/// The weight stage (`WeightStage`, docs/weights.md; its model's ports
/// [`crate::filter::weights::WeightInputs`], [`crate::filter::weights::WeightOutputs`]).
pub const WEIGHT_STAGE: Design = Design {
    name: "weight_stage",
    cli: Some("weights"),
    about: "`WeightStage` alone",
    prefix: "Vweights",
    params: Params::None,
    generator: "pficp_fpga::common::verilog::weight_stage_verilog",
    #[cfg(feature = "rtl")]
    verilog: |_| crate::common::verilog::weight_stage_verilog(),
    ports: &[
        i("clock", 1),
        i("clear", 1),
        i("cost_valid", 1),
        i("cost", COST_BITS),
        i("weigh", 1),
        i("pre_shift", PRE_SHIFT_BITS),
        i("q_mul", Q_MUL_BITS),
        o("busy", 1),
        o("count", count_bits(MAX_PARTICLES)),
        o("min_cost", COST_BITS),
        o("w_valid", 1),
        o("w_index", addr_bits(MAX_PARTICLES)),
        o("weight", WEIGHT_BITS),
        o("w_done", 1),
        o("w_sum", W_SUM_BITS),
    ],
    spec: "docs/weights.md (fpga/src/filter/weights_rtl.rs)",
};

/// The surface residual stage (`SurfaceResidual`, docs/pipeline.md "The surface residual";
/// its model's ports [`crate::surface::surface_residual::SurfaceInputs`],
/// [`crate::surface::surface_residual::SurfaceOutputs`]).
pub const SURFACE_RESIDUAL: Design = Design {
    name: "surface_residual",
    cli: Some("surface-residual"),
    about: "`SurfaceResidual`: the residual stage alone (no DSP48A1)",
    prefix: "Vsurf",
    params: Params::None,
    generator: "pficp_fpga::common::verilog::surface_residual_verilog",
    #[cfg(feature = "rtl")]
    verilog: |_| crate::common::verilog::surface_residual_verilog(),
    ports: &[
        i("clock", 1),
        i("point_we", 1),
        i("point_waddr", addr_bits(crate::surface::surface_residual::STORE_WORDS)),
        i("point_wdata", POINT_WORD_BITS),
        i("normal_we", 1),
        i("normal_waddr", addr_bits(crate::surface::surface_residual::STORE_WORDS)),
        i("normal_wdata", POINT_WORD_BITS),
        i("in_valid", 1),
        i("in_index", INDEX_BITS),
        i("in_dist", DIST_BITS),
        i("in_point", POINT_WORD_BITS),
        i("in_cost_valid", 1),
        o("nn_valid", 1),
        o("nn_index", INDEX_BITS),
        o("nn_dist", DIST_BITS),
        o("nn_resid", crate::surface::RESIDUAL_BITS),
        o("nn_s", SIGNED_RESIDUAL_BITS),
        o("nn_point", POINT_WORD_BITS),
        o("nn_normal", POINT_WORD_BITS),
        o("cost_valid", 1),
        o("cost", COST_BITS),
    ],
    spec: "docs/pipeline.md, the surface residual (fpga/src/surface/surface_residual_rtl.rs)",
};

/// The polish's datapath with its programs (`PolishProgram`).
pub const POLISH_PROGRAM: Design = Design {
    name: "polish_program",
    cli: Some("polish-program"),
    about: "`PolishProgram`: the polish's datapath with its programs in ROM (no DSP48A1)",
    prefix: "Vpolish",
    params: Params::None,
    generator: "pficp_fpga::common::verilog::polish_program_verilog",
    #[cfg(feature = "rtl")]
    verilog: |_| crate::common::verilog::polish_program_verilog(),
    ports: &[
        i("clock", 1),
        i("reset", 1),
        i("load", 1),
        i("load_addr", REGISTER_ADDR_BITS),
        i("load_data", crate::polish::program::REG_BITS),
        i("read_addr", REGISTER_ADDR_BITS),
        i("add", 1),
        i("add_addr", REGISTER_ADDR_BITS),
        i("add_data", crate::polish::program::ADD_BITS),
        i("go", 1),
        i("entry", ENTRY_BITS),
        o("read_data", crate::polish::program::REG_BITS),
        o("busy", 1),
        o("failed", 1),
    ],
    spec: "fpga/src/polish/program_rtl.rs",
};

/// The polish's blocks with a multiplier of their own (`PolishBench`).
pub const POLISH_BENCH: Design = Design {
    name: "polish_bench",
    cli: Some("polish-bench"),
    about: "`PolishBench`: the polish's pass, a multiplier and the datapath (on the board the multiplier is the \
            sequencer's)",
    prefix: "Vpbench",
    params: Params::None,
    generator: "pficp_fpga::common::verilog::polish_bench_verilog",
    #[cfg(feature = "rtl")]
    verilog: |_| crate::common::verilog::polish_bench_verilog(),
    ports: &[
        i("clock", 1),
        i("reset", 1),
        i("gated", 1),
        i("tau2", TAU2_BITS),
        i("scale_held", 1),
        i("t", TRANSLATION_BITS),
        i("in_valid", 1),
        i("in_q", POINT_WORD_BITS),
        i("in_n", POINT_WORD_BITS),
        i("in_s", PASS_RESIDUAL_BITS),
        o("ready", 1),
        i("flush", 1),
        o("idle", 1),
        i("load", 1),
        i("load_addr", REGISTER_ADDR_BITS),
        i("load_data", crate::polish::program::REG_BITS),
        i("read_addr", REGISTER_ADDR_BITS),
        o("read_data", crate::polish::program::REG_BITS),
        i("go", 1),
        i("entry", ENTRY_BITS),
        o("busy", 1),
        o("failed", 1),
    ],
    spec: "fpga/src/polish/bench_rtl.rs",
};

/// The whole polish as the board instantiates it, the multiplier's ports outside
/// (`PolishUnit`).
pub const POLISH_UNIT: Design = Design {
    name: "polish_unit",
    cli: Some("polish-unit"),
    about: "`PolishUnit`: the whole polish (control, datapath, pass) as the board instantiates it, the \
            multiplier's ports at the top",
    prefix: "Vpunit",
    params: Params::None,
    generator: "pficp_fpga::common::verilog::polish_unit_verilog",
    #[cfg(feature = "rtl")]
    verilog: |_| crate::common::verilog::polish_unit_verilog(),
    ports: &[
        i("clock", 1),
        i("reset", 1),
        i("go", 1),
        i("starts", STARTS_BITS),
        i("steps", STARTS_BITS),
        i("winner_steps", STARTS_BITS),
        i("scale_held", 1),
        i("start_pose", POSE_WORD_BITS),
        i("pass_done", 1),
        i("pass_cost", COST_BITS),
        i("in_valid", 1),
        i("in_q", POINT_WORD_BITS),
        i("in_n", POINT_WORD_BITS),
        i("in_s", PASS_RESIDUAL_BITS),
        i("mul_product", MUL_PRODUCT_BITS),
        o("start_index", STARTS_BITS),
        o("pass_go", 1),
        o("pose", POSE_WORD_BITS),
        o("ready", 1),
        o("mul_go", 1),
        o("mul_a", MUL_A_BITS),
        o("mul_b", MUL_B_BITS),
        o("busy", 1),
        o("done", 1),
        o("best_index", STARTS_BITS),
        o("best_cost", COST_BITS),
    ],
    spec: "fpga/src/polish/unit_rtl.rs",
};

/// The board's pins (`BoardTop`).
const BOARD_PORTS: &[Port] = &[i("clock", 1), i("reset_n", 1), i("uart_rx", 1), o("uart_tx", 1), o("leds", LED_BITS)];

/// The whole board (`BoardTop`), as shipped ([`BoardConfig::default`]).
pub const BOARD: Design = Design {
    name: "board",
    cli: Some("board"),
    about: "`BoardTop`: the board top `top` (clock, reset_n, uart_rx, uart_tx, leds[3:0])",
    prefix: "Vboard",
    params: Params::Board(BoardConfig::default),
    generator: "pficp_fpga::common::verilog::board_verilog",
    #[cfg(feature = "rtl")]
    verilog: crate::common::verilog::board_verilog,
    ports: BOARD_PORTS,
    spec: "fpga/src/board/top_rtl.rs",
};

/// The particle-filter sequencer alone (`PfSequencer`, docs/sequencer.md; its model's ports
/// [`crate::filter::sequencer::SeqInputs`], [`crate::filter::sequencer::SeqOutputs`]).
pub const SEQUENCER: Design = Design {
    name: "sequencer",
    cli: None,
    about: "`PfSequencer`: the particle filter's sequencer alone",
    prefix: "Vseq",
    params: Params::None,
    generator: "pficp_fpga::common::verilog::sequencer_verilog",
    #[cfg(feature = "rtl")]
    verilog: |_| crate::common::verilog::sequencer_verilog(),
    ports: &[
        i("clock", 1),
        i("reset", 1),
        i("cfg_we", 1),
        i("cfg_addr", addr_bits(crate::filter::pf::RUN_WORDS)),
        i("cfg_data", 8 * crate::filter::pf::RUN_WORD_BYTES as u32),
        i("go", 1),
        i("nn_ready", 1),
        i("cost_valid", 1),
        i("cost", COST_BITS),
        i("nn_valid", 1),
        i("nn_dist", DIST_BITS),
        i("ext_go", 1),
        i("ext_a", MUL_A_BITS),
        i("ext_b", MUL_B_BITS),
        o("start", 1),
        o("pose", POSE_WORD_BITS),
        o("running", 1),
        o("finished", 1),
        o("iterations", ITERATION_BITS),
        o("best_cost", COST_BITS),
        o("best_max", DIST_BITS),
        o("params", crate::filter::pf::PARAMS as u32 * crate::filter::pf::PARAM_BITS),
        o("p_we", 1),
        o("p_waddr", PARTICLE_ADDR_BITS),
        o("p_wdata", crate::filter::pf::PARAM_BITS),
        o("mul_product", MUL_PRODUCT_BITS),
    ],
    spec: "fpga/src/filter/sequencer_rtl.rs",
};

/// The board with the fast UART the co-simulation's fault and fuzz tests use
/// ([`BoardConfig::FAST_SIM`]).
pub const BOARD_FAST: Design = Design {
    name: "board_fast",
    cli: None,
    about: "`BoardTop` with the fast UART of the co-simulation's fault and fuzz tests",
    prefix: "Vboardfast",
    params: Params::Board(|| BoardConfig::FAST_SIM),
    generator: "pficp_fpga::common::verilog::board_verilog",
    #[cfg(feature = "rtl")]
    verilog: crate::common::verilog::board_verilog,
    ports: BOARD_PORTS,
    spec: "fpga/src/board/top_rtl.rs",
};

/// Every generated design, in the co-simulation's order (`verilated_models`); `hdl-gen`
/// lists its default, the board, first.
pub static DESIGNS: [Design; 9] = [
    NEIGHBOUR_PIPELINE,
    WEIGHT_STAGE,
    SURFACE_RESIDUAL,
    POLISH_PROGRAM,
    POLISH_BENCH,
    POLISH_UNIT,
    BOARD,
    SEQUENCER,
    BOARD_FAST,
];

/// The names of the output ports of `ports`, in order; `N` must be their count (checked at
/// compile time).
pub const fn outputs<const N: usize>(ports: &[Port]) -> [&'static str; N] {
    let mut out = [""; N];
    let (mut n, mut k) = (0, 0);
    while k < ports.len() {
        if !ports[k].input {
            out[n] = ports[k].name;
            n += 1;
        }
        k += 1;
    }
    assert!(n == N, "the output count is not N");
    out
}

/// The names of the output ports of `ports`, one per 64-bit word (a wide port repeats);
/// `N` must be the word count (checked at compile time).
pub const fn output_words<const N: usize>(ports: &[Port]) -> [&'static str; N] {
    let mut out = [""; N];
    let (mut n, mut k) = (0, 0);
    while k < ports.len() {
        if !ports[k].input {
            let mut w = 0;
            while w < ports[k].width.div_ceil(64) {
                out[n] = ports[k].name;
                n += 1;
                w += 1;
            }
        }
        k += 1;
    }
    assert!(n == N, "the output word count is not N");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The widths derived from the formats are the RTL's (as `Bits<N>` declares them).
    #[test]
    fn derived_widths() {
        assert_eq!((POSE_WORD_BITS, TRANSLATION_BITS, TABLE_ADDR_BITS, TABLE_DATA_BITS), (216, 54, 13, 13));
        assert_eq!((WEIGHT_BITS, W_SUM_BITS, count_bits(MAX_PARTICLES), addr_bits(MAX_PARTICLES)), (16, 24, 9, 8));
        assert_eq!((MUL_A_BITS, MUL_PRODUCT_BITS, PARTICLE_ADDR_BITS), (26, 44, 12));
        assert_eq!((REGISTER_ADDR_BITS, ENTRY_BITS, addr_bits(crate::filter::pf::RUN_WORDS)), (6, 9, 5));
    }

    #[test]
    fn names_are_unique() {
        for (k, d) in DESIGNS.iter().enumerate() {
            assert!(DESIGNS[..k]
                .iter()
                .all(|e| e.name != d.name && e.prefix != d.prefix && (d.cli.is_none() || e.cli != d.cli)));
            assert_eq!(d.ports[0], i("clock", 1), "{}", d.name);
        }
    }
}
