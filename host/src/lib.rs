//! PF-ICP host library: point-cloud registration in f64.
//!
//! Entry points, one line each:
//! - [`pf_icp::register`]: the paper's PF-ICP (k-means start, covariance, particle filter).
//! - [`icp::icp`]: ICP (Algorithm 1), with optional Welsch or Cauchy robust weights.
//! - [`sparse_icp::sparse_icp`] and [`em_icp::em_icp`]: the other baselines.
//! - [`datasets`]: the built-in models 1 to 3 and their scans.
//! - [`io`]: PLY, XYZ and CSV files.
#![warn(missing_docs)]

pub mod board;
pub mod cli;
pub mod cloud;
pub mod conclusion;
pub mod covariance;
pub mod datasets;
pub mod em_icp;
pub mod eval;
pub mod features;
pub mod geometry;
pub mod hessian;
pub mod hypotheses;
pub mod icp;
pub mod init;
pub mod io;
pub mod kmeans;
pub mod methods;
pub mod nn;
pub mod particle_filter;
pub mod parts;
pub mod pf_icp;
pub mod real_shapes;
pub mod sparse_icp;
pub mod surface;
pub mod svd_match;
#[cfg(test)]
mod test_support;
