//! The board around the pipeline (docs/protocol.md), one block a file:
//! - [`uart`]: `UartRx`, `UartTx` (8N1, the bit period set at generation, exact on average);
//! - [`crc`]: `Crc16Serial`, CRC-16/CCITT-FALSE a bit per clock;
//! - [`digest`]: `ModelDigest`, the model digest (CRC-32) a byte per clock;
//! - [`frame_rx`]: `FrameReceiver`, streaming COBS decode, CRC check, frame buffer writes;
//! - [`reply_tx`]: `ReplySender`, reply buffer, CRC and COBS encoder before the UART;
//! - [`engine`]: `CommandEngine<P>`, command execution, scan store, pipeline and weights;
//! - [`request_check`]: `RequestCheck`, a request's busy, command, length and capacity checks;
//! - [`scan_feeder`]: `ScanFeeder`, the scan store's points into the pipeline;
//! - [`pass_queue`]: `PassQueue`, the polish pass's found points between the pipeline and
//!   the pass;
//! - [`sequencer`]: `PfSequencer`, the on-board particle filter, and its arithmetic blocks;
//! - [`top`]: `BoardTop<P>`, pins, reset synchroniser, LEDs.
//!
//! The byte-level reference is [`crate::board::BoardModel`]: the Verilated board must send
//! the same bytes for the same bytes in (sim crate).

pub mod crc;
pub mod digest;
pub mod engine;
pub mod frame_rx;
pub mod pass_queue;
pub mod reply_tx;
pub mod request_check;
pub mod scan_feeder;
pub mod sequencer;
pub mod top;
pub mod uart;

pub use top::BoardTop;
