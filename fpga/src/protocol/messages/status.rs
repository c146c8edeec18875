//! Status: the on-board filter's state, iterations and best cost so far.

use super::{le, need, put, MessageError, COST_BYTES};

/// Data bytes of the Status reply: state, iterations, best cost.
pub const STATUS_BYTES: usize = 1 + 2 + COST_BYTES;
/// The best cost a Status reports before any run: `2^48 - 1`.
pub const NO_COST: u64 = crate::common::format::COST_MASK;

/// The on-board filter's state in a Status reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum RunState {
    /// No run since power-up or reset.
    Idle = 0,
    /// A filter is running.
    Running = 1,
    /// The last run finished; its result is ready.
    Done = 2,
}

impl RunState {
    /// The state of a byte.
    pub fn from_byte(b: u8) -> Option<RunState> {
        Some(match b {
            0 => RunState::Idle,
            1 => RunState::Running,
            2 => RunState::Done,
            _ => return None,
        })
    }
}

/// A Status reply: state, iterations completed, best cost so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StatusReply {
    /// The filter's state.
    pub state: RunState,
    /// Iterations completed (0 when idle).
    pub iterations: u16,
    /// Best cost so far (48 bits; [`NO_COST`] when idle).
    pub best_cost: u64,
}

impl StatusReply {
    /// The reply of a board that has not run the filter since power-up or reset.
    pub const IDLE: StatusReply = StatusReply { state: RunState::Idle, iterations: 0, best_cost: NO_COST };

    /// The reply data.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(STATUS_BYTES);
        out.push(self.state as u8);
        put(&mut out, self.iterations as u64, 2);
        put(&mut out, self.best_cost, COST_BYTES);
        out
    }

    /// Parse the reply data (length and state checked).
    pub fn decode(d: &[u8]) -> Result<Self, MessageError> {
        need(d, STATUS_BYTES)?;
        let state = RunState::from_byte(d[0]).ok_or(MessageError::Field {
            field: "state",
            got: d[0] as u64,
            expected: RunState::Done as u64,
        })?;
        Ok(StatusReply { state, iterations: le(&d[1..3]) as u16, best_cost: le(&d[3..9]) })
    }
}
