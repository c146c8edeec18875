//! [`Rtl`], what a Verilated design and its reference share: the interface the wrappers
//! (`wrappers/`) implement and the lockstep harness ([`LockstepOf`](crate::LockstepOf)) runs.
//! Both depend on it, neither on the other through it.

use std::fmt;
use std::path::Path;

/// A Verilated design and its reference, as [`LockstepOf`](crate::LockstepOf) runs them (implemented by
/// [`VerilatedNeighbourPipeline`](crate::VerilatedNeighbourPipeline),
/// [`VerilatedWeightStage`](crate::VerilatedWeightStage),
/// [`VerilatedSurfaceResidual`](crate::VerilatedSurfaceResidual) and
/// [`VerilatedSequencer`](crate::VerilatedSequencer)).
pub trait Rtl: Sized {
    /// The input ports.
    type Inputs: Copy + PartialEq + fmt::Debug;
    /// The output ports.
    type Outputs: Copy + PartialEq + fmt::Debug;
    /// The cycle-accurate reference.
    type Reference: Clone;
    /// Output port names, in the order they are compared.
    const OUTPUT_PORTS: &'static [&'static str];
    /// The output port values in [`OUTPUT_PORTS`](Self::OUTPUT_PORTS) order.
    fn port_values(o: &Self::Outputs) -> Vec<u64>;
    /// The reference after reset for this RTL.
    fn new_reference(&self) -> Self::Reference;
    /// The reference's outputs now.
    fn reference_outputs(r: &Self::Reference) -> Self::Outputs;
    /// One rising edge of the reference.
    fn reference_step(r: &mut Self::Reference, i: &Self::Inputs);
    /// A fresh instance of the same model, after reset.
    fn fresh(&self) -> Self;
    /// Drive the input ports.
    fn set_inputs(&mut self, i: &Self::Inputs);
    /// The output ports now.
    fn outputs(&self) -> Self::Outputs;
    /// One clock.
    fn tick(&mut self);
    /// Rising edges so far.
    fn cycle(&self) -> u64;
    /// Lanes (0 for a design without lanes).
    fn lanes(&self) -> usize;
    /// The Verilator prefix.
    fn prefix(&self) -> &'static str;
    /// Trace to a VCD from now on.
    fn trace_to(&mut self, path: &Path) -> std::io::Result<()>;
    /// Flush the VCD.
    fn flush_trace(&mut self);
}

/// The [`Rtl`] methods every wrapper forwards to its own methods and its `core`.
macro_rules! rtl_common {
    ($inputs:ty) => {
        fn set_inputs(&mut self, i: &$inputs) {
            Self::set_inputs(self, i)
        }
        fn outputs(&self) -> Self::Outputs {
            Self::outputs(self)
        }
        fn tick(&mut self) {
            self.core.tick()
        }
        fn cycle(&self) -> u64 {
            self.core.cycle
        }
        fn lanes(&self) -> usize {
            self.core.model.lanes
        }
        fn prefix(&self) -> &'static str {
            self.core.model.prefix
        }
        fn trace_to(&mut self, path: &Path) -> std::io::Result<()> {
            self.core.trace_to(path)
        }
        fn flush_trace(&mut self) {
            self.core.flush_trace()
        }
    };
}
