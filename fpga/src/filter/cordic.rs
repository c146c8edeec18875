//! The CORDIC: cosine and sine of a binary angle (Q2.16) in 18 steps, the model of
//! `cordic_rtl` (`Cordic`).

use super::params::wrap24;

/// Fraction bits of a sine or cosine (Q2.16).
pub const TRIG_FRAC: u32 = 16;
/// CORDIC iterations.
pub const CORDIC_STEPS: usize = 18;
/// `round(atan(2^-i) / 2 pi * 2^24)`: the CORDIC's angle steps in binary-angle units.
pub const CORDIC_ATAN: [i32; CORDIC_STEPS] =
    [2097152, 1238021, 654136, 332050, 166669, 83416, 41718, 20860, 10430, 5215, 2608, 1304, 652, 326, 163, 81, 41, 20];
/// The CORDIC's start `x`: `round(K * 2^18)`, `K = prod 1 / sqrt(1 + 2^-2i)` over 18 steps.
pub const CORDIC_K: i32 = 159188;
/// Fraction bits inside the CORDIC (two guard bits over the output).
pub const CORDIC_FRAC: u32 = 18;

/// Cosine and sine of a binary angle (Q2.16), by an 18-step CORDIC: angles beyond a
/// quarter turn are turned by half a turn first and the result negated.
pub fn cordic(angle: i32) -> (i32, i32) {
    let a = wrap24(angle as i64);
    let flip = !(-(1 << 22)..=(1 << 22)).contains(&a);
    let mut z = if flip { wrap24(a as i64 - (1 << 23)) as i64 } else { a as i64 };
    let (mut x, mut y) = (CORDIC_K as i64, 0i64);
    for (i, &t) in CORDIC_ATAN.iter().enumerate() {
        let (dx, dy) = (y >> i, x >> i);
        if z >= 0 {
            x -= dx;
            y += dy;
            z -= t as i64;
        } else {
            x += dx;
            y -= dy;
            z += t as i64;
        }
    }
    let round = |v: i64| ((v + 2) >> 2) as i32;
    let (c, s) = (round(x), round(y));
    if flip {
        (-c, -s)
    } else {
        (c, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn turn(deg: f64) -> i32 {
        wrap24((deg / 360.0 * (1u64 << 24) as f64).round() as i64)
    }

    #[test]
    fn cordic_is_within_three_lsb_everywhere() {
        for k in -720..=720 {
            let deg = k as f64 * 0.5 + 0.123;
            let (c, s) = cordic(turn(deg));
            let r = deg.to_radians();
            let scale = (1u64 << TRIG_FRAC) as f64;
            assert!((c as f64 - r.cos() * scale).abs() <= 3.0, "cos {deg}: {c}");
            assert!((s as f64 - r.sin() * scale).abs() <= 3.0, "sin {deg}: {s}");
        }
    }
}
