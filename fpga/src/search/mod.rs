//! The nearest-neighbour search: the model's cell grid, the transform, the neighbour
//! pipeline (the board's search) and what they share.
//!
//! - [`grid`]: the model's cell grid and the grid search's bit-exact reference (capped at
//!   one cell);
//! - [`pipeline`]: what the search shares with its references (result ports, transform
//!   stages, scan-stream driver) and the plain brute-force reference; its RTL is
//!   `transform_rtl` (`Transform`: the pose register and 9 `Mul18`) and `mul18_rtl`
//!   (`Mul18`, a registered 18 x 18 signed multiplier, one DSP48A1);
//! - [`neighbour_pipeline`]: the cycle-accurate reference of the neighbour pipeline (lanes
//!   over one scan point's candidates in its 27 cells) and its functional reference over the
//!   board's stores; its RTL twin `neighbour_pipeline_rtl` (`NeighbourPipeline<P>`), whose
//!   lanes and model-RAM banks are `neighbour_lane_rtl` (`NeighbourLane`, `BankRam`).

pub mod grid;
#[cfg(feature = "rtl")]
pub mod mul18_rtl;
#[cfg(feature = "rtl")]
pub mod neighbour_lane_rtl;
pub mod neighbour_pipeline;
#[cfg(feature = "rtl")]
pub mod neighbour_pipeline_rtl;
pub mod pipeline;
#[cfg(feature = "rtl")]
pub mod transform_rtl;
