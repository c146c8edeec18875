//! The board: its generation parameters and (below) the byte-level reference of the whole
//! board (docs/protocol.md): given the bytes in, the bytes out.

/// What a board is generated with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoardConfig {
    /// Pipeline lanes (one of the RTL's supported counts).
    pub lanes: usize,
    /// Design clock in Hz (the oscillator; no DCM).
    pub clock_hz: u32,
    /// Nominal UART baud rate.
    pub baud: u32,
}

impl Default for BoardConfig {
    fn default() -> Self {
        BoardConfig { lanes: 16, clock_hz: 100_000_000, baud: 921_600 }
    }
}

impl BoardConfig {
    /// Clocks per UART bit: `round(clock_hz / baud)`.
    pub fn bit_clocks(&self) -> u32 {
        ((self.clock_hz as u64 + self.baud as u64 / 2) / self.baud as u64) as u32
    }

    /// The baud rate the board really runs at (`clock_hz / bit_clocks`).
    pub fn actual_baud(&self) -> f64 {
        self.clock_hz as f64 / self.bit_clocks() as f64
    }
}
