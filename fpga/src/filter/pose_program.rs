//! The pose of a particle: the CORDIC's cosines and sines and the scale through the pose
//! program ([`POSE_PROGRAM`], a ROM in the RTL) into the pose matrix, and the translation;
//! the model of `pose_program_rtl` (`PoseProgram`).

use super::cordic::cordic;
use super::params::{sat18, Particle, SCALE};
use super::translation::translation;
use crate::common::format::FxPose;

/// One step of the pose program ([`POSE_PROGRAM`]) over the 32-entry register file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `r[dst] = (r[a] * r[b] + 2^15) >> 16` (`r[b]` taken as 18-bit signed).
    Mul16 {
        /// Destination register.
        dst: u8,
        /// Wide operand.
        a: u8,
        /// 18-bit operand.
        b: u8,
    },
    /// `r[dst] = sat18((r[a] * r[b] + 2^21) >> 22)`: scale (Q3.21) times a rotation entry
    /// (Q2.16) to a pose matrix entry (Q3.15).
    MulM {
        /// Destination register.
        dst: u8,
        /// Wide operand.
        a: u8,
        /// 18-bit operand.
        b: u8,
    },
    /// `r[dst] = r[a] + r[b]`.
    Add {
        /// Destination register.
        dst: u8,
        /// Operand.
        a: u8,
        /// Operand.
        b: u8,
    },
    /// `r[dst] = r[a] - r[b]`.
    Sub {
        /// Destination register.
        dst: u8,
        /// Operand.
        a: u8,
        /// Operand.
        b: u8,
    },
}

/// Registers of the pose program: `cos phi, sin phi, cos theta, sin theta, cos psi,
/// sin psi` in 0..6, the scale in 6, zero in 31; the pose matrix lands in 21..30.
pub const REG_SCALE: u8 = 6;
/// First register of the pose matrix (row-major, nine).
pub const REG_M: u8 = 21;
/// The register that always reads zero.
pub const REG_ZERO: u8 = 31;

/// `s R`, `R = Rz(psi) Ry(theta) Rx(phi)`, in 14 products, 5 sums and 9 scalings. The RTL
/// holds it in a ROM ([`Op::encode`]) and runs it step by step.
pub const POSE_PROGRAM: [Op; 28] = {
    use Op::*;
    [
        Mul16 { dst: 7, a: 4, b: 2 },   // cpsi ctheta = R00
        Mul16 { dst: 8, a: 5, b: 2 },   // spsi ctheta = R10
        Mul16 { dst: 9, a: 4, b: 3 },   // cpsi stheta
        Mul16 { dst: 10, a: 5, b: 3 },  // spsi stheta
        Mul16 { dst: 11, a: 9, b: 1 },  // cpsi stheta sphi
        Mul16 { dst: 12, a: 9, b: 0 },  // cpsi stheta cphi
        Mul16 { dst: 13, a: 10, b: 1 }, // spsi stheta sphi
        Mul16 { dst: 14, a: 10, b: 0 }, // spsi stheta cphi
        Mul16 { dst: 15, a: 5, b: 0 },  // spsi cphi
        Mul16 { dst: 16, a: 5, b: 1 },  // spsi sphi
        Mul16 { dst: 17, a: 4, b: 0 },  // cpsi cphi
        Mul16 { dst: 18, a: 4, b: 1 },  // cpsi sphi
        Mul16 { dst: 19, a: 2, b: 1 },  // ctheta sphi = R21
        Mul16 { dst: 20, a: 2, b: 0 },  // ctheta cphi = R22
        Sub { dst: 11, a: 11, b: 15 },  // R01
        Add { dst: 12, a: 12, b: 16 },  // R02
        Add { dst: 13, a: 13, b: 17 },  // R11
        Sub { dst: 14, a: 14, b: 18 },  // R12
        Sub { dst: 15, a: 31, b: 3 },   // R20 = -stheta
        MulM { dst: 21, a: 6, b: 7 },
        MulM { dst: 22, a: 6, b: 11 },
        MulM { dst: 23, a: 6, b: 12 },
        MulM { dst: 24, a: 6, b: 8 },
        MulM { dst: 25, a: 6, b: 13 },
        MulM { dst: 26, a: 6, b: 14 },
        MulM { dst: 27, a: 6, b: 15 },
        MulM { dst: 28, a: 6, b: 19 },
        MulM { dst: 29, a: 6, b: 20 },
    ]
};

impl Op {
    /// The ROM word: kind (2 bits: Mul16, MulM, Add, Sub) | dst << 2 | a << 7 | b << 12.
    pub const fn encode(self) -> u32 {
        let (kind, dst, a, b) = match self {
            Op::Mul16 { dst, a, b } => (0, dst, a, b),
            Op::MulM { dst, a, b } => (1, dst, a, b),
            Op::Add { dst, a, b } => (2, dst, a, b),
            Op::Sub { dst, a, b } => (3, dst, a, b),
        };
        kind | (dst as u32) << 2 | (a as u32) << 7 | (b as u32) << 12
    }
}

/// Bits of a register-file entry.
pub const REG_BITS: u32 = 26;

/// The 18-bit operand of a multiply: the low 18 bits, sign-extended.
pub fn operand18(v: i64) -> i64 {
    (v << 46) >> 46
}

/// Run the pose program on a register file (entries wrap to 26 bits).
pub fn run_program(r: &mut [i64; 32]) {
    let wrap = |v: i64| (v << (64 - REG_BITS)) >> (64 - REG_BITS);
    for op in POSE_PROGRAM {
        match op {
            Op::Mul16 { dst, a, b } => {
                r[dst as usize] = wrap((r[a as usize] * operand18(r[b as usize]) + (1 << 15)) >> 16)
            }
            Op::MulM { dst, a, b } => {
                r[dst as usize] = sat18((r[a as usize] * operand18(r[b as usize]) + (1 << 21)) >> 22) as i64
            }
            Op::Add { dst, a, b } => r[dst as usize] = wrap(r[a as usize] + r[b as usize]),
            Op::Sub { dst, a, b } => r[dst as usize] = wrap(r[a as usize] - r[b as usize]),
        }
        r[REG_ZERO as usize] = 0;
    }
}

/// The pose of a particle, exactly as the sequencer builds it.
pub fn pose_of(p: &Particle) -> FxPose {
    let mut r = [0i64; 32];
    for k in 0..3 {
        let (c, s) = cordic(p[4 + k]);
        r[2 * k] = c as i64;
        r[2 * k + 1] = s as i64;
    }
    r[REG_SCALE as usize] = p[SCALE] as i64;
    run_program(&mut r);
    FxPose { m: std::array::from_fn(|k| r[REG_M as usize + k] as i32), t: std::array::from_fn(|k| translation(p[k])) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::format::{MATRIX_FRAC, POSE_BITS};
    use crate::filter::params::{wrap24, SCALE_FRAC};

    fn turn(deg: f64) -> i32 {
        wrap24((deg / 360.0 * (1u64 << 24) as f64).round() as i64)
    }

    #[test]
    fn pose_of_matches_the_float_rotation() {
        let (phi, theta, psi, s) = (20.0f64, -35.0f64, 170.0f64, 1.3f64);
        let p: Particle =
            [1 << 19, -(1 << 18), 12345, (s * (1 << SCALE_FRAC) as f64) as i32, turn(phi), turn(theta), turn(psi)];
        let pose = pose_of(&p);
        let (cf, sf) = (phi.to_radians().cos(), phi.to_radians().sin());
        let (ct, st) = (theta.to_radians().cos(), theta.to_radians().sin());
        let (cp, sp) = (psi.to_radians().cos(), psi.to_radians().sin());
        let r = [
            cp * ct,
            cp * st * sf - sp * cf,
            cp * st * cf + sp * sf,
            sp * ct,
            sp * st * sf + cp * cf,
            sp * st * cf - cp * sf,
            -st,
            ct * sf,
            ct * cf,
        ];
        for (k, (&m, r)) in pose.m.iter().zip(r).enumerate() {
            let want = s * r * (1 << MATRIX_FRAC) as f64;
            assert!((m as f64 - want).abs() <= 8.0, "m[{k}] {m} vs {want}");
        }
        assert_eq!(pose.t, [1 << 13, -(1 << 12), translation(12345)]);
        const { assert!(POSE_BITS == 18) };
    }
}
