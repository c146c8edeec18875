//! A translation parameter to the pose's translation, the model of `translation_rtl`
//! (`Translation`).

use super::params::sat18;

/// The translation of a pose: `T_i = sat18((x + 2^5) >> 6)` (Q5.19 to Q5.13).
pub fn translation(x: i32) -> i32 {
    sat18((x as i64 + 32) >> 6)
}
