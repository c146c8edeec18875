//! Fixed-point formats shared by the host, the bit-exact reference and the RTL.
//!
//! All values are two's-complement integers; `Qm.n` means `m` integer bits (sign
//! included) and `n` fraction bits. The host normalises both clouds so that the model
//! fits in the unit ball (see docs/fixed-point.md); everything below is in those
//! normalised units.
//!
//! | quantity | type | format | range | LSB |
//! |---|---|---|---|---|
//! | point coordinate (model, scan, transformed scan) | `i16` | Q3.13 | [-4, 4) | 2^-13 |
//! | pose matrix entry `(sR)_ij` | 18-bit | Q3.15 | [-4, 4) | 2^-15 |
//! | pose translation `T_i` | 18-bit | Q5.13 | [-16, 16) | 2^-13 |
//! | coordinate difference | 17-bit | Q4.13 | (-8, 8) | 2^-13 |
//! | squared distance | 34-bit unsigned | Q8.26 | [0, 192) | 2^-26 |
//! | particle cost (sum of squared distances) | 48-bit unsigned | Q22.26 | | 2^-26 |
//! | weight | 16-bit unsigned | Q0.16 | [0, 1) | 2^-16 |
//!
//! Rounding: the transform rounds half up (add `2^14`, arithmetic shift right by 15) and
//! saturates to `i16`. Squares and sums are exact. Nothing else rounds.

/// Fraction bits of a coordinate.
pub const COORD_FRAC: u32 = 13;
/// Fraction bits of a pose matrix entry.
pub const MATRIX_FRAC: u32 = 15;
/// Fraction bits of a pose translation, Q5.13 (same as coordinates; the filter's translation
/// parameters are [`crate::filter::pf::PARAM_TRANSLATION_FRAC`]).
pub const POSE_TRANSLATION_FRAC: u32 = 13;
/// Bits of a pose matrix entry and translation.
pub const POSE_BITS: u32 = 18;
/// Fraction bits of a squared distance and a cost.
pub const DIST_FRAC: u32 = 2 * COORD_FRAC;
/// Bits of a squared distance (`3 * (2^16 - 1)^2 < 2^34`).
pub const DIST_BITS: u32 = 34;
/// Bits of a particle cost.
pub const COST_BITS: u32 = 48;
/// Mask of a cost (48 bits); costs wrap at it, and its value means "no cost yet".
pub const COST_MASK: u64 = (1 << COST_BITS) - 1;
/// Most particles the board holds (the weight stage's costs, the filter's set).
pub const MAX_PARTICLES: usize = 256;
/// Largest model and scan: 4,096 points (12-bit index).
pub const MAX_POINTS: usize = 4096;
/// Bits of a point index.
pub const INDEX_BITS: u32 = 12;

/// A fixed-point point: `[x, y, z]` in Q3.13.
pub type FxPoint = [i16; 3];

/// A fixed-point pose: `x' = M m + T`, `M = s R` in Q3.15, `T` in Q5.13 (both 18-bit,
/// kept in `i32`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct FxPose {
    /// Row-major `s R`.
    pub m: [i32; 9],
    /// Translation.
    pub t: [i32; 3],
}

/// Largest value of a signed `bits`-bit integer.
pub const fn smax(bits: u32) -> i64 {
    (1i64 << (bits - 1)) - 1
}

/// Smallest value of a signed `bits`-bit integer.
pub const fn smin(bits: u32) -> i64 {
    -(1i64 << (bits - 1))
}

/// Round `x * 2^frac` to nearest (half away from zero is not used: half up, as the RTL)
/// and saturate to a signed `bits`-bit integer.
pub fn quantise(x: f64, frac: u32, bits: u32) -> i64 {
    let scaled = (x * (1u64 << frac) as f64 + 0.5).floor();
    if scaled.is_nan() {
        return 0;
    }
    (scaled.clamp(smin(bits) as f64, smax(bits) as f64)) as i64
}

/// A coordinate to Q3.13 (saturating).
pub fn coord(x: f64) -> i16 {
    quantise(x, COORD_FRAC, 16) as i16
}

/// A Q3.13 coordinate back to f64.
pub fn coord_to_f64(x: i16) -> f64 {
    x as f64 / (1u64 << COORD_FRAC) as f64
}

/// A point to fixed point.
pub fn point(p: [f64; 3]) -> FxPoint {
    [coord(p[0]), coord(p[1]), coord(p[2])]
}

impl FxPose {
    /// Quantise `s R` (row-major) and `T`.
    pub fn from_f64(m: &[f64; 9], t: &[f64; 3]) -> FxPose {
        FxPose {
            m: m.map(|v| quantise(v, MATRIX_FRAC, POSE_BITS) as i32),
            t: t.map(|v| quantise(v, POSE_TRANSLATION_FRAC, POSE_BITS) as i32),
        }
    }

    /// Pack into the 216-bit pose word of the RTL: `m[0]` in bits 0..18, ..., `m[8]`, then
    /// `t[0..3]`, each field 18-bit two's complement. Returned as little-endian u64 words.
    pub fn pack(&self) -> [u64; 4] {
        let mut w = [0u64; 4];
        let fields = self.m.iter().chain(self.t.iter());
        for (k, &v) in fields.enumerate() {
            let bits = (v as i64 as u64) & ((1 << POSE_BITS) - 1);
            let at = k as u32 * POSE_BITS;
            let (word, off) = ((at / 64) as usize, at % 64);
            w[word] |= bits << off;
            if off + POSE_BITS > 64 {
                w[word + 1] |= bits >> (64 - off);
            }
        }
        w
    }
}

/// Pack a translation as the pose word holds it (18-bit two's complement fields, `t[0]` in
/// bits 0..18): the 54-bit `t` port of the polish's pass.
pub fn pack_translation(t: [i32; 3]) -> u64 {
    t.iter()
        .enumerate()
        .fold(0, |w, (k, &v)| w | ((v as i64 as u64) & ((1 << POSE_BITS) - 1)) << (k as u32 * POSE_BITS))
}

/// Bits of a packed point (the model and scan memory word).
pub const POINT_WORD_BITS: u32 = 48;

/// Pack a point into the 48-bit memory word: x in bits 0..16, y in 16..32, z in 32..48.
pub fn pack_point(p: FxPoint) -> u64 {
    (p[0] as u16 as u64) | ((p[1] as u16 as u64) << 16) | ((p[2] as u16 as u64) << 32)
}

/// Unpack a 48-bit memory word.
pub fn unpack_point(w: u64) -> FxPoint {
    [w as u16 as i16, (w >> 16) as u16 as i16, (w >> 32) as u16 as i16]
}

/// The transform of one point, exactly as the RTL computes it (indices as in the RTL):
/// `x'_i = sat16((sum_j m_ij * p_j + (t_i << 15) + 2^14) >> 15)`.
#[allow(clippy::needless_range_loop)]
pub fn transform(pose: &FxPose, p: FxPoint) -> FxPoint {
    let mut out = [0i16; 3];
    for i in 0..3 {
        let mut acc: i64 = (pose.t[i] as i64) << MATRIX_FRAC;
        for j in 0..3 {
            acc += pose.m[3 * i + j] as i64 * p[j] as i64;
        }
        let r = (acc + (1 << (MATRIX_FRAC - 1))) >> MATRIX_FRAC;
        out[i] = r.clamp(i16::MIN as i64, i16::MAX as i64) as i16;
    }
    out
}

/// Squared distance of two points (exact, Q8.26).
pub fn dist2(a: FxPoint, b: FxPoint) -> u64 {
    (0..3)
        .map(|k| {
            let d = a[k] as i64 - b[k] as i64;
            (d * d) as u64
        })
        .sum()
}

/// A Q8.26 squared distance (or a Q22.26 cost) to f64.
pub fn dist_to_f64(d: u64) -> f64 {
    d as f64 / (1u64 << DIST_FRAC) as f64
}

/// Entries of the exp table.
pub const EXP_ENTRIES: usize = 256;
/// Table steps per e-fold: entry `j` is `exp(-j / EXP_STEPS_PER_E)`.
pub const EXP_STEPS_PER_E: f64 = 32.0;

/// The weight table: `round(65535 * exp(-j / 32))`, `j = 0..256`.
pub fn exp_table() -> [u16; EXP_ENTRIES] {
    std::array::from_fn(|j| (65535.0 * (-(j as f64) / EXP_STEPS_PER_E).exp()).round() as u16)
}

/// How a cost excess becomes a table index: `j = min(255, ((dc >> pre_shift) sat 17 bits) * q_mul >> 16)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct WeightScale {
    /// Right shift of the cost excess before the multiply.
    pub pre_shift: u32,
    /// Unsigned 17-bit multiplier (Q1.16).
    pub q_mul: u32,
}

/// Largest cost excess after the pre-shift (17-bit unsigned saturation).
pub const EXCESS_MAX: u64 = (1 << 17) - 1;

impl WeightScale {
    /// The scale for a likelihood `exp(-dc / (2 Q))` with `two_q` in cost LSBs
    /// (`2^-26` normalised units squared): index `j = 32 dc / (2 Q)`.
    pub fn for_two_q(two_q: f64) -> WeightScale {
        // j = dc * 32 / two_q = (dc >> pre) * q_mul / 2^16  =>  q_mul = 32 * 2^(16 + pre) / two_q.
        // The largest pre-shift that keeps q_mul within 17 bits gives the most precision.
        let two_q = two_q.max(1.0);
        let q_mul_at = |pre: u32| (EXP_STEPS_PER_E * (1u64 << (16 + pre)) as f64 / two_q).round();
        let mut pre = 0u32;
        while pre < 47 && q_mul_at(pre + 1) < (1 << 17) as f64 {
            pre += 1;
        }
        WeightScale { pre_shift: pre, q_mul: q_mul_at(pre).clamp(1.0, EXCESS_MAX as f64) as u32 }
    }

    /// Table index of a cost excess.
    pub fn index(&self, excess: u64) -> usize {
        let e = (excess >> self.pre_shift).min(EXCESS_MAX);
        ((e * self.q_mul as u64) >> 16).min(EXP_ENTRIES as u64 - 1) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantise_rounds_half_up_and_saturates() {
        assert_eq!(coord(1.0), 8192);
        assert_eq!(coord(-4.0), -32768);
        assert_eq!(coord(5.0), 32767);
        assert_eq!(coord(-5.0), -32768);
        assert_eq!(quantise(0.5 / 8192.0, 13, 16), 1);
        assert_eq!(quantise(-0.5 / 8192.0, 13, 16), 0);
        assert_eq!(coord(f64::NAN), 0);
    }

    #[test]
    fn transform_matches_f64_within_half_lsb() {
        let pose = FxPose::from_f64(&[0.6, -0.8, 0.0, 0.8, 0.6, 0.0, 0.0, 0.0, 1.0], &[0.25, -0.5, 0.125]);
        let p = point([0.3, -0.7, 0.9]);
        let q = transform(&pose, p);
        let f = |v: i16| coord_to_f64(v);
        let exact = [0.6 * f(p[0]) - 0.8 * f(p[1]) + 0.25, 0.8 * f(p[0]) + 0.6 * f(p[1]) - 0.5, f(p[2]) + 0.125];
        for i in 0..3 {
            assert!((f(q[i]) - exact[i]).abs() <= 0.5 / 8192.0 + 1e-12, "{i}: {} vs {}", f(q[i]), exact[i]);
        }
    }

    #[test]
    fn transform_saturates() {
        let pose = FxPose {
            m: [(1 << 17) - 1, 0, 0, 0, (1 << 17) - 1, 0, 0, 0, (1 << 17) - 1],
            t: [(1 << 17) - 1, -(1 << 17), 0],
        };
        assert_eq!(transform(&pose, [i16::MAX, i16::MIN, 0]), [i16::MAX, i16::MIN, 0]);
    }

    #[test]
    fn pack_round_trips() {
        let p = [-1, 32767, -32768];
        assert_eq!(unpack_point(pack_point(p)), p);
        let pose = FxPose { m: [1, -1, 2, -2, 131071, -131072, 0, 5, -5], t: [7, -7, 100] };
        let w = pose.pack();
        let field = |k: u32| -> i64 {
            let at = k * 18;
            let lo = w[(at / 64) as usize] >> (at % 64);
            let hi = if at % 64 + 18 > 64 { w[(at / 64) as usize + 1] << (64 - at % 64) } else { 0 };
            let raw = (lo | hi) & ((1 << 18) - 1);
            ((raw << 46) as i64) >> 46
        };
        for k in 0..9 {
            assert_eq!(field(k), pose.m[k as usize] as i64);
        }
        for k in 0..3 {
            assert_eq!(field(9 + k), pose.t[k as usize] as i64);
        }
    }

    #[test]
    fn exp_table_and_scale() {
        let t = exp_table();
        assert_eq!(t[0], 65535);
        assert_eq!(t[32], (65535.0 * (-1.0f64).exp()).round() as u16);
        assert!(t.windows(2).all(|w| w[1] <= w[0]));
        for two_q in [1.0, 1000.0, 3.7e6, 1e12] {
            let s = WeightScale::for_two_q(two_q);
            let dc = two_q as u64;
            let j = s.index(dc) as f64;
            if two_q >= 8.0 {
                assert!((j - 32.0).abs() <= 1.0, "2Q {two_q}: j {j} {s:?}");
            }
        }
        assert_eq!(WeightScale::for_two_q(100.0).index(u64::MAX), 255);
    }
}
