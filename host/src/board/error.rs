//! What can go wrong talking to the board: one typed error a case, each message one line
//! naming the port and the request.

use pficp_fpga::protocol::messages::{MessageError, RunState};
use pficp_fpga::protocol::{Command, ErrorCode};
use std::time::Duration;

/// What went wrong talking to the board.
#[derive(Debug, thiserror::Error)]
pub enum BoardError {
    /// The serial port could not be opened.
    #[error("cannot open serial port {path}: {reason}")]
    Open {
        /// The path asked for.
        path: String,
        /// Why.
        reason: String,
    },
    /// Reading or writing the port failed (e.g. the adapter was unplugged).
    #[error("serial port {port}: {error} while {during} (was the board unplugged?)")]
    Io {
        /// The port.
        port: String,
        /// What the client was doing.
        during: String,
        /// The error (in the message only, so it is printed once).
        error: std::io::Error,
    },
    /// No reply within the time allowed.
    #[error(
        "the board on {port} did not answer {command:?} within {} ms{} (is it connected, configured and set to {baud} baud? \
         a board slower than its clock says, such as the simulated one, needs a larger --timeout-ms)",
        waited.as_millis(),
        noise_note(*.received)
    )]
    Timeout {
        /// The port.
        port: String,
        /// The request.
        command: Command,
        /// Time waited for the reply.
        waited: Duration,
        /// The port's baud rate.
        baud: u32,
        /// Bytes that arrived during the wait without making a reply.
        received: usize,
    },
    /// Only replies with another sequence number or for another command arrived in the time
    /// allowed (a board that numbers its replies wrongly, or another device on the port).
    #[error(
        "the board on {port} did not answer {command:?} (sequence {seq}) within {} ms; it sent a reply \
         {} with sequence {got_seq} instead",
        waited.as_millis(),
        reply_name(*.got_code)
    )]
    Unexpected {
        /// The port.
        port: String,
        /// The request.
        command: Command,
        /// The request's sequence number.
        seq: u8,
        /// The command code of the last reply that was not ours.
        got_code: u8,
        /// Its sequence number.
        got_seq: u8,
        /// Time waited.
        waited: Duration,
    },
    /// The port sent back the request itself: a loopback adapter or a tty in echo mode, not
    /// a board.
    #[error(
        "{port} sends back what is written to it ({command:?} came back as sent): a loopback adapter or a \
         terminal in echo mode, not the board"
    )]
    Echo {
        /// The port.
        port: String,
        /// The request that came back.
        command: Command,
    },
    /// Identify got no valid reply at any of the baud rates tried ([`super::BoardClient::connect`]
    /// without a rate).
    #[error(
        "the board on {port} did not answer Identify at any baud rate tried: {} (is it connected and configured? \
         --baud gives its rate; a board slower than its clock says, such as the simulated one, needs a larger --timeout-ms)",
        tried.iter().map(|(b, why)| format!("{b} ({why})")).collect::<Vec<_>>().join(", ")
    )]
    NoAnswer {
        /// The port.
        port: String,
        /// Each rate tried, in order, and why it gave no answer.
        tried: Vec<(u32, String)>,
    },
    /// Identify answered at one baud rate, but the board says it was generated for another
    /// (a line that ignores the rate, such as a pseudo-terminal).
    #[error(
        "the board on {port} answered Identify at {opened} baud but says it runs at {reported} baud \
         (a line that ignores the rate?); give --baud {reported}"
    )]
    BaudMismatch {
        /// The port.
        port: String,
        /// The rate the port was opened at.
        opened: u32,
        /// The rate the board reports.
        reported: u32,
    },
    /// The board answered with an error reply.
    #[error("the board answered {command:?} with error {code:?} ({})", *code as u8)]
    Board {
        /// The request.
        command: Command,
        /// The board's error code.
        code: ErrorCode,
    },
    /// Every attempt of a request ended in a corrupted exchange.
    #[error("no valid reply to {command:?} after {attempts} attempts (last: {last})")]
    Retries {
        /// The request.
        command: Command,
        /// Attempts made.
        attempts: usize,
        /// The last problem.
        last: String,
    },
    /// The reply to a request that is not repeatable was lost (the board may have executed it).
    #[error("the reply to {command:?} was lost ({reason}) and the request is not repeatable")]
    ReplyLost {
        /// The request.
        command: Command,
        /// What happened to the reply.
        reason: String,
    },
    /// A reply with a valid CRC whose contents do not fit the request.
    #[error("malformed reply to {command:?}: {problem}")]
    Reply {
        /// The request.
        command: Command,
        /// What does not fit (in the message only).
        problem: MessageError,
    },
    /// The request does not fit the board's limits (checked on the host).
    #[error("{0}")]
    Limit(String),
    /// The particle filter stopped for a reason of its own.
    #[error("the particle filter stopped: {0}")]
    Filter(String),
    /// The on-board filter stalled: the board answers Status and says "running", but its
    /// iteration count did not move for the whole allowance, or the run took longer than
    /// the allowance for every iteration.
    #[error(
        "the board on {port} did not finish the filter: no new iteration for {} ms, {} ms since Run \
         (allowed: {} ms without a new iteration, {} ms in all; {} ms modelled board time for the whole run); \
         last Status: {state:?}, {iterations} iterations",
        waited.as_millis(),
        total.as_millis(),
        stall_limit.as_millis(),
        overall_limit.as_millis(),
        modelled.as_millis()
    )]
    RunTimeout {
        /// The port.
        port: String,
        /// The time allowed without a new iteration.
        stall_limit: Duration,
        /// The time allowed in all.
        overall_limit: Duration,
        /// Time waited since the iteration count last changed (or since the wait began).
        waited: Duration,
        /// Time waited in all.
        total: Duration,
        /// The modelled board time of the run.
        modelled: Duration,
        /// The last Status state.
        state: RunState,
        /// Iterations the last Status reported.
        iterations: u16,
    },
}

/// The Timeout message's note on bytes that came but made no reply.
fn noise_note(received: usize) -> String {
    if received == 0 {
        String::new()
    } else {
        format!(" ({received} bytes came that were no valid reply: line noise, a wrong baud rate or another device?)")
    }
}

/// A reply code by its command's name.
fn reply_name(code: u8) -> String {
    Command::from_code(code).map_or_else(|| format!("with code {code:#04x}"), |c| format!("to {c:?}"))
}
