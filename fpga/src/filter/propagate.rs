//! A particle's parameter after propagation, the model of `propagate_rtl` (`Propagate`).

use super::params::wrap24;

/// A particle's parameter after propagation: `x` moved by `sigma u` (`u` a signed 16-bit
/// draw, Q1.15; doubled on the first iteration, where the particles start at the centre)
/// around `centre`, clamped to `+-2 sigma` of it; a scale is kept positive.
pub fn propagate(x: i32, centre: i32, sigma: u32, u: i64, first: bool, scale: bool) -> i32 {
    let prod = sigma as i64 * u;
    let step = if first { prod >> 14 } else { prod >> 15 };
    let base = if first { 0 } else { wrap24(x as i64 - centre as i64) as i64 };
    let lim = 2 * sigma as i64;
    let off = (base + step).clamp(-lim, lim);
    positive_scale(wrap24(centre as i64 + off), scale)
}

/// A scale of zero or below becomes the smallest positive one.
pub(super) fn positive_scale(v: i32, scale: bool) -> i32 {
    if scale && v <= 0 {
        1
    } else {
        v
    }
}
