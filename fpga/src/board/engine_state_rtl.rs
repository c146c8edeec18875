//! The command engine's states ([`super::CommandEngine`]).

use rust_hdl::prelude::*;

/// Engine states.
#[derive(Copy, Clone, Debug, PartialEq, Eq, LogicState)]
pub enum EngState {
    /// Waiting for a frame (or a pending Busy answer).
    Idle,
    /// The six header bytes are in: the checks register the sums they need.
    Decode,
    /// The checks register their verdict.
    Check,
    /// Busy and NoResult from the filter's state, the checks' verdict, or the command.
    Dispatch,
    /// Fetch: put the frame buffer address.
    FetchAddr,
    /// Fetch: take the byte.
    FetchData,
    /// Emit: append the next byte of `outbuf` when the sender is ready.
    Emit,
    /// Start a reply: command | 0x80 and sequence.
    Header,
    /// Start an error reply.
    ErrHeader,
    /// Append the CRC and transmit.
    Send,
    /// Wait for the last byte to leave.
    SendWait,
    /// Identify: the data bytes before the model digest.
    IdBody,
    /// Identify: the model digest.
    IdDigest,
    /// LoadModel / LoadTable: the request's four header bytes into the model digest.
    DigHead,
    /// Load: next point or done.
    LoadNext,
    /// Load: write the fetched point.
    LoadWrite,
    /// Load / SetSizes reply: the 4 header bytes back.
    EchoBody,
    /// Evaluate: clear the stored costs with FIRST.
    EvBegin,
    /// Evaluate: next pose or done.
    EvNext,
    /// Evaluate: start the pipeline on the fetched pose.
    EvRun,
    /// Evaluate: wait for the cost.
    EvWait,
    /// Evaluate: count the pose.
    EvInc,
    /// Evaluate: all poses done; weigh with LAST.
    EvDone,
    /// Evaluate: collect the weights.
    WeighWait,
    /// Evaluate: the summary (stored, min cost, weight sum).
    SumEmit,
    /// Evaluate: next weight or done.
    WLoop,
    /// Evaluate: append a weight.
    WRead,
    /// Nearest: start the pipeline on the fetched pose.
    NrRun,
    /// Nearest: collect results and the cost.
    NrWait,
    /// Nearest: first, count, cost.
    NrHead,
    /// Nearest: next result or done.
    NrLoop,
    /// Nearest: append a result.
    NrRead,
    /// Run: the polish word is in: check its points, keep it.
    RunPolish,
    /// Run: next configuration word or the hypotheses.
    RunNext,
    /// Run: next hypothesis pose or the header word.
    RunHyp,
    /// Run: keep the fetched hypothesis.
    RunHypWrite,
    /// Run: write the fetched word.
    RunWrite,
    /// Run: start the sequencer, answer.
    RunGo,
    /// Status: the 9 data bytes.
    StBody,
    /// Result: iterations, cost, largest distance.
    ResBody1,
    /// Result: the parameters.
    ResBody2,
    /// Result: the filter's pose.
    ResBody3,
    /// Result: the polish's winner and cost.
    ResBody4,
    /// Result: the polished pose.
    ResBody5,
}
