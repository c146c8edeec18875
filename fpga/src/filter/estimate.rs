//! A parameter's estimate and next spread from the weighted sums, the model of
//! `estimate_rtl` (`Estimate`).

use super::params::wrap24;
use super::propagate::positive_scale;
use super::serial_div::div_signed;

/// A parameter's estimate: `centre + S / W` (`S` the weighted sum of the particles' offsets
/// from the centre); a scale is kept positive.
pub fn estimate_param(centre: i32, s: i64, w_sum: u32, scale: bool) -> i32 {
    positive_scale(wrap24(centre as i64 + div_signed(s, w_sum)), scale)
}

/// A parameter's next spread: `1.25 D / W` (`D` the weighted sum of the particles' distances
/// from the estimate) within `[floor, cap]`.
pub fn spread(dsum: u64, w_sum: u32, floor: u32, cap: u32) -> u32 {
    let dev = dsum / w_sum as u64;
    (dev + (dev >> 2)).clamp(floor as u64, cap as u64) as u32
}
