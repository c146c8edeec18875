//! The Verilog of each design (feature `rtl`): the whole board ([`board_verilog`]) and the
//! blocks the co-simulation runs alone, each from its RTL block beside its model, through
//! [`super::rtl`]'s post-processing (repeated modules, attributes, waivers).

use super::rtl::{dedup_modules, distributed_register_files, waive_probe_ports, waive_unused_wires, BOARD_LANES};
use rust_hdl::prelude::*;

/// The Verilog of the weight stage alone, top module `top` (docs/weights.md).
pub fn weight_stage_verilog() -> String {
    let mut uut = crate::filter::weights_rtl::WeightStage::new();
    uut.connect_all();
    dedup_modules(&generate_verilog(&uut))
}

/// The Verilog of the residual stage alone (`SurfaceResidual`, docs/pipeline.md "The
/// surface residual"), top module `top`.
pub fn surface_residual_verilog() -> String {
    let mut uut = crate::surface::surface_residual_rtl::SurfaceResidual::new();
    uut.connect_all();
    dedup_modules(&generate_verilog(&uut))
}

/// The Verilog of the polish's datapath alone with the polish's programs in ROM
/// (`PolishProgram::polish`, docs/polish-datapath.md), top module
/// `top`; the register file marked `ram_style = "distributed"`
/// ([`distributed_register_files`]).
pub fn polish_program_verilog() -> String {
    let mut uut = crate::polish::program_rtl::PolishProgram::polish();
    uut.connect_all();
    distributed_register_files(&dedup_modules(&generate_verilog(&uut)))
}

/// The Verilog of the polish's blocks with a multiplier of their own (`PolishBench`: the
/// pass, a `PipeMul` and the program's datapath), top module `top`; the register file
/// marked as in [`polish_program_verilog`]; the multiplier's `busy` and `valid`, which the
/// pass does not need (it counts the clocks), waived as unused.
pub fn polish_bench_verilog() -> String {
    let mut uut = crate::polish::bench_rtl::PolishBench::new();
    uut.connect_all();
    let v = distributed_register_files(&dedup_modules(&generate_verilog(&uut)));
    waive_unused_wires(&v, &["mul$busy", "mul$valid"])
}

/// The Verilog of the whole polish as the board instantiates it (`PolishUnit`: the
/// control, the program's datapath and the pass; the multiplier's ports at the top), top
/// module `top`; the register file marked as in [`polish_program_verilog`]; the datapath's
/// `read_data` above the 32 bits the control reads (a pose field, `TAU2`) waived as unused.
pub fn polish_unit_verilog() -> String {
    let mut uut = crate::polish::unit_rtl::PolishUnit::new();
    uut.connect_all();
    let v = distributed_register_files(&dedup_modules(&generate_verilog(&uut)));
    waive_unused_wires(&v, &["prog$read_data"])
}

fn neighbour_of<const P: usize>() -> String {
    let mut uut = crate::search::neighbour_pipeline_rtl::NeighbourPipeline::<P>::new();
    uut.connect_all();
    dedup_modules(&generate_verilog(&uut))
}

/// The Verilog of `NeighbourPipeline<lanes>` (lanes over one scan point's candidates,
/// docs/pipeline.md "The neighbour pipeline"), top module `top`.
///
/// Panics unless `lanes` is one of [`BOARD_LANES`].
pub fn neighbour_pipeline_verilog(lanes: usize) -> String {
    match lanes {
        2 => neighbour_of::<2>(),
        4 => neighbour_of::<4>(),
        8 => neighbour_of::<8>(),
        16 => neighbour_of::<16>(),
        _ => panic!("neighbour_pipeline_verilog: {lanes} lanes is not supported; use one of {BOARD_LANES:?}"),
    }
}

fn board_of<const P: usize>(config: &crate::board::BoardConfig) -> String {
    let mut uut = crate::board::top_rtl::BoardTop::<P>::new(config);
    uut.connect_all();
    waive_probe_ports(&dedup_modules(&generate_verilog(&uut)))
}

/// The Verilog of the whole board (`BoardTop<lanes>`, top module `top`, pins `clock`,
/// `reset_n`, `uart_rx`, `uart_tx`, `leds[3:0]`) as `config` says.
///
/// Panics unless `config.lanes` is one of [`BOARD_LANES`] and the UART has at least 4
/// clocks per bit.
pub fn board_verilog(config: &crate::board::BoardConfig) -> String {
    match config.lanes {
        2 => board_of::<2>(config),
        4 => board_of::<4>(config),
        8 => board_of::<8>(config),
        16 => board_of::<16>(config),
        n => panic!("board_verilog: {n} lanes is not supported; use one of {BOARD_LANES:?}"),
    }
}

/// Verilog of the particle-filter sequencer alone (`PfSequencer`, the co-simulation's unit).
pub fn sequencer_verilog() -> String {
    let mut uut = crate::filter::sequencer_rtl::PfSequencer::new();
    uut.connect_all();
    dedup_modules(&generate_verilog(&uut))
}
