//! Every Verilated design's ports, in one place: `build.rs` checks the Verilated headers
//! against them and writes the shim's port copies from them; the wrappers take the names
//! of the outputs they compare from them ([`outputs`], [`output_words`]). Each list is the
//! order of the packed input and output arrays the shim exchanges with Rust; the RTL
//! structs in `fpga/src` are where the ports are declared.

/// A port: (name, is_input, width). `clock` is driven by `tick`.
pub type PortSpec = (&'static str, bool, usize);

/// The ports of the neighbour pipeline's `top` (docs/pipeline.md, "The neighbour pipeline"),
/// in the order of the packed input/output arrays the shim exchanges with Rust.
pub const NEIGHBOUR_PIPELINE_PORTS: &[PortSpec] = &[
    ("clock", true, 1),
    ("model_we", true, 1),
    ("model_waddr", true, 12),
    ("model_wdata", true, 48),
    ("table_we", true, 1),
    ("table_waddr", true, 13),
    ("table_wdata", true, 13),
    ("start", true, 1),
    ("pose", true, 216),
    ("scan_valid", true, 1),
    ("scan_data", true, 48),
    ("scan_last", true, 1),
    ("scan_ready", false, 1),
    ("busy", false, 1),
    ("nn_valid", false, 1),
    ("nn_index", false, 12),
    ("nn_dist", false, 34),
    ("cost_valid", false, 1),
    ("cost", false, 48),
    ("nn_point", false, 48),
];

/// The ports of the weight stage (docs/weights.md).
pub const WEIGHT_STAGE_PORTS: &[PortSpec] = &[
    ("clock", true, 1),
    ("clear", true, 1),
    ("cost_valid", true, 1),
    ("cost", true, 48),
    ("weigh", true, 1),
    ("pre_shift", true, 6),
    ("q_mul", true, 17),
    ("busy", false, 1),
    ("count", false, 9),
    ("min_cost", false, 48),
    ("w_valid", false, 1),
    ("w_index", false, 8),
    ("weight", false, 16),
    ("w_done", false, 1),
    ("w_sum", false, 24),
];

/// The ports of the surface residual stage (docs/pipeline.md, "The surface residual").
pub const SURFACE_RESIDUAL_PORTS: &[PortSpec] = &[
    ("clock", true, 1),
    ("point_we", true, 1),
    ("point_waddr", true, 12),
    ("point_wdata", true, 48),
    ("normal_we", true, 1),
    ("normal_waddr", true, 12),
    ("normal_wdata", true, 48),
    ("in_valid", true, 1),
    ("in_index", true, 12),
    ("in_dist", true, 34),
    ("in_point", true, 48),
    ("in_cost_valid", true, 1),
    ("nn_valid", false, 1),
    ("nn_index", false, 12),
    ("nn_dist", false, 34),
    ("nn_resid", false, 21),
    ("nn_s", false, 14),
    ("nn_point", false, 48),
    ("nn_normal", false, 48),
    ("cost_valid", false, 1),
    ("cost", false, 48),
];

/// The pins of the board top (`fpga/src/board/top_rtl.rs`).
pub const BOARD_PORTS: &[PortSpec] =
    &[("clock", true, 1), ("reset_n", true, 1), ("uart_rx", true, 1), ("uart_tx", false, 1), ("leds", false, 4)];

/// The ports of the particle-filter sequencer (`fpga/src/filter/sequencer_rtl.rs`).
pub const SEQUENCER_PORTS: &[PortSpec] = &[
    ("clock", true, 1),
    ("reset", true, 1),
    ("cfg_we", true, 1),
    ("cfg_addr", true, 5),
    ("cfg_data", true, 48),
    ("go", true, 1),
    ("nn_ready", true, 1),
    ("cost_valid", true, 1),
    ("cost", true, 48),
    ("nn_valid", true, 1),
    ("nn_dist", true, 34),
    ("ext_go", true, 1),
    ("ext_a", true, 26),
    ("ext_b", true, 18),
    ("start", false, 1),
    ("pose", false, 216),
    ("running", false, 1),
    ("finished", false, 1),
    ("iterations", false, 16),
    ("best_cost", false, 48),
    ("best_max", false, 34),
    ("params", false, 168),
    ("p_we", false, 1),
    ("p_waddr", false, 12),
    ("p_wdata", false, 24),
    ("mul_product", false, 44),
];

/// The ports of the polish's datapath (`fpga/src/polish/program_rtl.rs`).
pub const POLISH_PROGRAM_PORTS: &[PortSpec] = &[
    ("clock", true, 1),
    ("reset", true, 1),
    ("load", true, 1),
    ("load_addr", true, 6),
    ("load_data", true, 128),
    ("read_addr", true, 6),
    ("add", true, 1),
    ("add_addr", true, 6),
    ("add_data", true, 48),
    ("go", true, 1),
    ("entry", true, 9),
    ("read_data", false, 128),
    ("busy", false, 1),
    ("failed", false, 1),
];

/// The ports of the polish's blocks with their multiplier (`fpga/src/polish/bench_rtl.rs`).
pub const POLISH_BENCH_PORTS: &[PortSpec] = &[
    ("clock", true, 1),
    ("reset", true, 1),
    ("gated", true, 1),
    ("tau2", true, 32),
    ("t", true, 54),
    ("in_valid", true, 1),
    ("in_q", true, 48),
    ("in_n", true, 48),
    ("in_s", true, 13),
    ("ready", false, 1),
    ("flush", true, 1),
    ("idle", false, 1),
    ("load", true, 1),
    ("load_addr", true, 6),
    ("load_data", true, 128),
    ("read_addr", true, 6),
    ("read_data", false, 128),
    ("go", true, 1),
    ("entry", true, 9),
    ("busy", false, 1),
    ("failed", false, 1),
];

/// The ports of the whole polish (`fpga/src/polish/unit_rtl.rs`).
pub const POLISH_UNIT_PORTS: &[PortSpec] = &[
    ("clock", true, 1),
    ("reset", true, 1),
    ("go", true, 1),
    ("starts", true, 4),
    ("steps", true, 4),
    ("winner_steps", true, 4),
    ("start_pose", true, 216),
    ("pass_done", true, 1),
    ("pass_cost", true, 48),
    ("in_valid", true, 1),
    ("in_q", true, 48),
    ("in_n", true, 48),
    ("in_s", true, 13),
    ("mul_product", true, 44),
    ("start_index", false, 4),
    ("pass_go", false, 1),
    ("pose", false, 216),
    ("ready", false, 1),
    ("mul_go", false, 1),
    ("mul_a", false, 26),
    ("mul_b", false, 18),
    ("busy", false, 1),
    ("done", false, 1),
    ("best_index", false, 4),
    ("best_cost", false, 48),
];

/// The names of the output ports of `lists` (concatenated), in order; `N` must be their
/// count (checked at compile time).
pub const fn outputs<const N: usize>(lists: &[&[PortSpec]]) -> [&'static str; N] {
    let mut out = [""; N];
    let (mut n, mut l) = (0, 0);
    while l < lists.len() {
        let mut i = 0;
        while i < lists[l].len() {
            if !lists[l][i].1 {
                out[n] = lists[l][i].0;
                n += 1;
            }
            i += 1;
        }
        l += 1;
    }
    assert!(n == N, "the output count is not N");
    out
}

/// The names of the output ports of `ports`, one per 64-bit word (a wide port repeats);
/// `N` must be the word count (checked at compile time).
pub const fn output_words<const N: usize>(ports: &[PortSpec]) -> [&'static str; N] {
    let mut out = [""; N];
    let (mut n, mut i) = (0, 0);
    while i < ports.len() {
        if !ports[i].1 {
            let mut w = 0;
            while w < ports[i].2.div_ceil(64) {
                out[n] = ports[i].0;
                n += 1;
                w += 1;
            }
        }
        i += 1;
    }
    assert!(n == N, "the output word count is not N");
    out
}
