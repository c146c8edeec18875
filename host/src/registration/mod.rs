//! ICP and the baselines the paper compares PF-ICP with, and the one call that runs any
//! of them or PF-ICP ([`methods::run`]):
//! - [`icp`]: ICP (Algorithm 1), point-to-point or point-to-plane, optional Welsch or
//!   Cauchy weights, with scale;
//! - [`sparse_icp`]: Sparse ICP (an l_p norm by ADMM);
//! - [`em_icp`]: EM-ICP (soft assignments);
//! - [`svd_match`]: the closed-form similarity of matched pairs (Umeyama) that all use;
//! - [`methods`]: the method names and the dispatch.

pub mod em_icp;
pub mod icp;
pub mod methods;
pub mod sparse_icp;
pub mod svd_match;
