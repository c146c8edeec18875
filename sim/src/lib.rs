//! Verilator co-simulation harness: lands with the pipeline issue.
