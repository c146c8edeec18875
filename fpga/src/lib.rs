//! PF-ICP hardware side.
//!
//! This crate will hold the fixed-point formats, the bit-exact reference model of the
//! particle-weight pipeline and the wire protocol (shared with the host), and, behind the
//! `rtl` feature, the rust_hdl RTL. Nothing is implemented here yet: the pipeline lands
//! with issue 3 and the board link with issue 4.
#![warn(missing_docs)]
