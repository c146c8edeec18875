//! PF-ICP host library: point-cloud registration in f64, and the host side of the board.
//!
//! The tree follows the data path:
//! - [`io`] reads and writes PLY, PCD, XYZ and CSV clouds into a [`cloud::Cloud`]; [`geometry`]
//!   holds poses, transforms and the scale's bounds, [`nn`] the nearest-neighbour search
//!   every method uses, [`visibility`] what a sensor at a point sees of a cloud.
//! - [`request::Request`]: one registration (method, engine, settings), checked and run;
//!   what the CLI's `register` calls.
//! - [`pf_icp`]: PF-ICP ([`pf_icp::register`]): k-means start and global search, ICP
//!   covariance, particle filter, polish, conclusion and verdict, one module each.
//! - [`registration`]: ICP (Algorithm 1, [`registration::icp::icp`]) and the other
//!   baselines, and [`registration::methods::run`], which runs any of them or PF-ICP.
//! - [`board`]: the board client over the serial line, the on-board and host-driven
//!   modes, the fixed-point bridge to the board's formats.
//! - [`datasets`], [`parts`], [`real_shapes`]: the built-in models 1 to 3 and their scans,
//!   the synthetic parts and the real shapes of the realistic benchmark.
//! - [`eval`]: the paper's experiments and the realistic benchmark; [`cli`]: the CLI's
//!   reports.
#![warn(missing_docs)]

pub mod board;
pub mod cli;
pub mod cloud;
pub mod datasets;
pub mod demo;
pub mod eval;
pub mod geometry;
pub mod io;
pub mod nn;
pub mod parts;
pub mod pf_icp;
pub mod progress;
pub mod real_shapes;
pub mod registration;
pub mod request;
#[cfg(test)]
mod test_support;
pub mod tracking;
pub mod visibility;
