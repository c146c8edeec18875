//! The board top (`BoardTop`): its wrapper, pins only.

use crate::core::*;
use pficp_fpga::board::BoardConfig;
use pficp_fpga::designs;
use std::fmt;
use std::path::Path;

/// The Verilated board top (`BoardTop`, `fpga/src/board/top_rtl.rs`): pins only.
pub struct VerilatedBoard {
    pub(crate) core: Core,
}

/// The board's pins after an edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BoardPins {
    /// The serial line to the host.
    pub uart_tx: bool,
    /// The LEDs (0 heartbeat, 1 receive activity, 2 busy, 3 error).
    pub leds: u8,
}

/// The input pins of the board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoardInputs {
    /// Reset, active low.
    pub reset_n: bool,
    /// The serial line from the host (high when idle).
    pub uart_rx: bool,
}

impl Default for BoardInputs {
    fn default() -> Self {
        BoardInputs { reset_n: true, uart_rx: true }
    }
}

verilated_common!(VerilatedBoard, BoardInputs);

impl VerilatedBoard {
    /// The board generated as `config` says: [`BoardConfig::default`] (the real board) or
    /// [`BoardConfig::FAST_SIM`] (the fast UART the fault tests use); pins idle.
    ///
    /// Panics for any other configuration (only those two are verilated).
    pub fn new(config: &BoardConfig) -> Self {
        let design = if *config == BoardConfig::default() {
            designs::BOARD.name
        } else if *config == BoardConfig::FAST_SIM {
            designs::BOARD_FAST.name
        } else {
            panic!("no Verilated board for {config:?}: only BoardConfig::default() and BoardConfig::FAST_SIM are built")
        };
        let mut b = VerilatedBoard { core: Core::new(design, 0, 2, &["uart_tx", "leds"]) };
        b.set_inputs(&BoardInputs::default());
        b
    }

    /// Drive the input pins.
    pub fn set_inputs(&mut self, i: &BoardInputs) {
        self.core.set_inputs(&[i.reset_n as u64, i.uart_rx as u64])
    }

    /// The output pins now.
    pub fn pins(&self) -> BoardPins {
        let o = self.core.outputs::<2>();
        BoardPins { uart_tx: o[0] != 0, leds: o[1] as u8 }
    }
}
