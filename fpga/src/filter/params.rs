//! The filter's parameters: the seven of a particle and their fixed-point formats
//! (docs/sequencer.md), with the wrap and the saturation every block uses.

/// Parameters per particle: `[a, b, c, s, phi, theta, psi]`.
pub const PARAMS: usize = 7;
/// Index of the scale parameter.
pub const SCALE: usize = 3;
/// Fraction bits of a translation parameter, Q5.19 (the pose built from it has
/// [`crate::common::format::POSE_TRANSLATION_FRAC`]).
pub const PARAM_TRANSLATION_FRAC: u32 = 19;
/// Fraction bits of the scale parameter (Q3.21).
pub const SCALE_FRAC: u32 = 21;
/// Bits of a parameter (angles: a full turn).
pub const PARAM_BITS: u32 = 24;
/// Bits of a sigma.
pub const SIGMA_BITS: u32 = 22;

/// A particle: `[a, b, c, s, phi, theta, psi]` in the formats above.
pub type Particle = [i32; PARAMS];

/// Wrap to a 24-bit two's-complement value.
pub fn wrap24(x: i64) -> i32 {
    ((x << 40) >> 40) as i32
}

/// Saturate to an 18-bit two's-complement value.
pub fn sat18(x: i64) -> i32 {
    x.clamp(-(1 << 17), (1 << 17) - 1) as i32
}
