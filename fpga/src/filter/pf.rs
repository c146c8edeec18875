//! The on-board particle filter (PF-ICP Algorithm 6, steps 6 to 8) in bit-exact integer
//! arithmetic: the functional reference of the RTL sequencer (`filter::sequencer_rtl`)
//! and of the board's Run command (docs/sequencer.md).
//!
//! Everything here is integers with the formats below; the RTL computes the same values
//! with a pipelined multiplier, a serial divider and a CORDIC, and its cycle-accurate mirror
//! ([`crate::filter::sequencer`]) is checked against [`run`] and against the Verilated RTL.
//!
//! | quantity | bits | format |
//! |---|---|---|
//! | translation parameter `a, b, c` | 24 signed | Q5.19 |
//! | scale parameter `s` | 24 signed | Q3.21 |
//! | angle parameter `phi, theta, psi` | 24 | binary angle: a full turn is `2^24` (wraps) |
//! | sigma (per parameter) | 22 unsigned | the parameter's LSBs |
//! | sine, cosine | 18 signed | Q2.16 |
//! | weight | 16 unsigned | Q0.16 (the exp table of [`crate::common::format::exp_table`]) |
//!
//! Every parameter is handled modulo `2^24`: an offset from the region centre is the
//! wrapped 24-bit difference, which for angles is exactly the wrap-around-free offset the
//! circular mean needs (the region is never wider than half a turn).

use crate::common::format::{exp_table, FxPose, EXP_ENTRIES};

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
pub use crate::common::format::MAX_PARTICLES;
/// Words of a Run request after its header (each [`RUN_WORD_BYTES`], little-endian).
pub const RUN_WORDS: usize = 24;
/// Data bytes of a Run request.
pub const RUN_BYTES: usize = RUN_HEADER_BYTES + RUN_WORD_BYTES * RUN_WORDS;
/// Bytes of a Run request's header: particles, iterations, temperature exponent.
pub const RUN_HEADER_BYTES: usize = 6;
/// Bytes of one Run word (48 bits).
pub const RUN_WORD_BYTES: usize = 6;
/// The smallest temperature exponent (`2 Q_k >= 2^5` cost LSBs; `q_mul` stays `2^16`).
pub const MIN_TEMPER_EXP: u32 = 5;

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

/// The Run parameters (the prior from the host's k-means start and ICP covariance).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PfConfig {
    /// Particles `n_p` (1..=256).
    pub particles: u16,
    /// Iteration cap (>= 1).
    pub iterations: u16,
    /// `e_Q`: the ICP variance as a power of two, `2 Q = 2^e_Q` cost LSBs (6 bits).
    pub temper_exp: u8,
    /// Centre of the first region (the start).
    pub centre: Particle,
    /// Initial sigma per parameter (22 bits; also the cap of the region update).
    pub sigma0: [u32; PARAMS],
    /// Smallest sigma per parameter (22 bits).
    pub floor: [u32; PARAMS],
    /// PRNG seed (0 is taken as 1).
    pub seed: u32,
    /// Stop when the best cost is at most this (cost LSBs) ...
    pub thr_cost: u64,
    /// ... and its largest squared point distance at most this (34 bits, distance LSBs).
    pub thr_max: u64,
}

/// Why a Run request's data is not a [`PfConfig`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ConfigError {
    /// Not [`RUN_BYTES`] bytes.
    #[error("a Run request has {RUN_BYTES} data bytes, not {0}")]
    Length(usize),
    /// Particles not in 1..=256 or no iterations.
    #[error("{0} particles and {1} iterations (1..=256 particles, at least 1 iteration)")]
    Capacity(u16, u16),
    /// A polish over no points or more than the scan store holds
    /// ([`crate::protocol::run_request::RunRequest`]).
    #[error("a polish over {0} scan points (1..=4096)")]
    Points(u16),
}

fn le(b: &[u8]) -> u64 {
    b.iter().rev().fold(0u64, |a, &x| (a << 8) | x as u64)
}

impl PfConfig {
    /// The Run request's data: `particles` u16, `iterations` u16, `temper_exp` u8, a zero
    /// byte, then 24 words of 6 bytes: centre[7], sigma0[7], floor[7], seed, thr_cost,
    /// thr_max.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(RUN_BYTES);
        out.extend(self.particles.to_le_bytes());
        out.extend(self.iterations.to_le_bytes());
        out.push(self.temper_exp);
        out.push(0);
        let words = self
            .centre
            .iter()
            .map(|&c| c as u32 as u64 & 0xff_ffff)
            .chain(self.sigma0.iter().map(|&s| s as u64))
            .chain(self.floor.iter().map(|&s| s as u64))
            .chain([self.seed as u64, self.thr_cost, self.thr_max]);
        for w in words {
            out.extend(&w.to_le_bytes()[..RUN_WORD_BYTES]);
        }
        out
    }

    /// Parse a Run request's data, with the board's checks (length, then capacities).
    /// Fields are taken as the board takes them: sigma and floor masked to 22 bits, the
    /// temperature exponent to 6, the centre sign-extended from 24 bits, thr_max masked
    /// to 34 bits.
    pub fn decode(d: &[u8]) -> Result<PfConfig, ConfigError> {
        if d.len() != RUN_BYTES {
            return Err(ConfigError::Length(d.len()));
        }
        let particles = u16::from_le_bytes([d[0], d[1]]);
        let iterations = u16::from_le_bytes([d[2], d[3]]);
        if particles == 0 || particles as usize > MAX_PARTICLES || iterations == 0 {
            return Err(ConfigError::Capacity(particles, iterations));
        }
        let at = |i: usize| RUN_HEADER_BYTES + RUN_WORD_BYTES * i;
        let w = |i: usize| le(&d[at(i)..at(i + 1)]);
        let sigma = |i: usize| (w(i) & ((1 << SIGMA_BITS) - 1)) as u32;
        Ok(PfConfig {
            particles,
            iterations,
            temper_exp: d[4] & 63,
            centre: std::array::from_fn(|i| wrap24(w(i) as i64)),
            sigma0: std::array::from_fn(|i| sigma(PARAMS + i)),
            floor: std::array::from_fn(|i| sigma(2 * PARAMS + i)),
            seed: w(21) as u32,
            thr_cost: w(22),
            thr_max: w(23) & ((1 << 34) - 1),
        })
    }
}

/// The PRNG: xorshift32 (13, 17, 5). A seed of 0 is taken as 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Xorshift32(pub u32);

impl Xorshift32 {
    /// Seeded.
    pub fn new(seed: u32) -> Self {
        Xorshift32(if seed == 0 { 1 } else { seed })
    }
    /// The next state (also the output). Not an `Iterator`: the stream never ends and every
    /// draw's width is chosen by the caller ([`Self::signed16`], [`Self::unsigned16`]).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }
    /// A signed 16-bit draw (the top half of the next state): `u` in `[-1, 1)` as Q1.15.
    pub fn signed16(&mut self) -> i32 {
        (self.next() >> 16) as u16 as i16 as i32
    }
    /// An unsigned 16-bit draw: `u` in `[0, 1)` as Q0.16.
    pub fn unsigned16(&mut self) -> u32 {
        self.next() >> 16
    }
}

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

/// The translation of a pose: `T_i = sat18((x + 2^5) >> 6)` (Q5.19 to Q5.13).
pub fn translation(x: i32) -> i32 {
    sat18((x as i64 + 32) >> 6)
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

/// What the pipeline gives for one pose: the cost and the largest squared point distance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Evaluated {
    /// Sum of squared nearest distances (48 bits).
    pub cost: u64,
    /// Largest squared nearest distance (34 bits).
    pub max_d2: u64,
}

impl Evaluated {
    /// The cost and the largest squared distance of a pipeline's evaluation.
    pub fn of(e: &crate::search::pipeline::Evaluation) -> Evaluated {
        Evaluated { cost: e.cost, max_d2: e.nearest.iter().map(|n| n.1).max().unwrap_or(0) }
    }
}

/// The board's answer for a pose, by the functional reference: the grid search over the
/// gridded model (the stored points and their table), every distance capped at
/// `grid::CAP_D2` (docs/pipeline.md, "The neighbour pipeline").
pub fn evaluate(grid: &crate::search::grid::Grid, scan: &[crate::common::format::FxPoint], pose: &FxPose) -> Evaluated {
    Evaluated::of(&crate::search::grid::evaluate_grid(grid, scan, pose))
}

/// One iteration, as the sequencer leaves it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IterationRecord {
    /// The propagated particles that were weighed.
    pub particles: Vec<Particle>,
    /// Their costs.
    pub costs: Vec<u64>,
    /// Temperature exponent `e_k` (`2 Q_k = 2^e_k`).
    pub temper: u32,
    /// Their weights.
    pub weights: Vec<u16>,
    /// Sum of the weights.
    pub w_sum: u32,
    /// The weighted estimate.
    pub estimate: Particle,
    /// Its evaluation.
    pub estimate_eval: Evaluated,
    /// Sigma after the region update.
    pub sigma: [u32; PARAMS],
    /// Best cost so far.
    pub best_cost: u64,
    /// The centre of the next iteration (the best particle or estimate so far).
    pub centre: Particle,
    /// The resampled set (empty after the last iteration).
    pub resampled: Vec<Particle>,
}

/// The filter's result.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PfOutcome {
    /// Best particle or estimate seen.
    pub params: Particle,
    /// Its pose.
    pub pose: FxPose,
    /// Its evaluation.
    pub best: Evaluated,
    /// Iterations run.
    pub iterations: u16,
    /// The start's evaluation.
    pub start: Evaluated,
    /// Per iteration.
    pub history: Vec<IterationRecord>,
}

/// The temperature exponent: `e = max(e_Q, bitlen(m) - 2, 5)` with `m` the excess of rank
/// `n / 2` (0-based) among the sorted excesses `c_i - c_min`: `2 Q_k = 2^e` lies between a
/// quarter and a half of the median excess, or is the ICP variance's `2 Q` if larger.
pub fn temper(excess: &[u64], temper_exp: u8) -> u32 {
    let k = excess.len() / 2;
    let b = (0..=48u32).find(|&p| excess.iter().filter(|&&e| p == 48 || e < (1u64 << p)).count() > k).unwrap_or(48);
    (temper_exp as u32 & 63).max(b.saturating_sub(2)).max(MIN_TEMPER_EXP)
}

/// A weight: `EXP[min(255, excess >> (e - 5))]`.
pub fn weight(excess: u64, e: u32, table: &[u16; EXP_ENTRIES]) -> u16 {
    let j = (excess >> (e - MIN_TEMPER_EXP)).min(EXP_ENTRIES as u64 - 1);
    table[j as usize]
}

/// `|S| / W` with the sign of `S` (truncation toward zero).
pub fn div_signed(s: i64, w: u32) -> i64 {
    let q = (s.unsigned_abs() / w as u64) as i64;
    if s < 0 {
        -q
    } else {
        q
    }
}

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

/// A scale of zero or below becomes the smallest positive one.
fn positive_scale(v: i32, scale: bool) -> i32 {
    if scale && v <= 0 {
        1
    } else {
        v
    }
}

/// Systematic resampling on integer weights: pointer `j` is `(u0 + j 2^16) W`, compared
/// with `n 2^16 CDF_i`; `i` advances while the pointer is strictly beyond.
pub fn resample(weights: &[u16], w_sum: u32, u0: u32) -> Vec<usize> {
    let n = weights.len() as u64;
    let mut picks = Vec::with_capacity(weights.len());
    let mut left = u0 as u64 * w_sum as u64;
    let mut i = 0usize;
    let mut right = (n * weights[0] as u64) << 16;
    for _ in 0..weights.len() {
        while left > right && i + 1 < weights.len() {
            i += 1;
            right += (n * weights[i] as u64) << 16;
        }
        picks.push(i);
        left += (w_sum as u64) << 16;
    }
    picks
}

/// Run the filter; `eval` is the pipeline (cost and largest squared distance of a pose).
pub fn run(cfg: &PfConfig, mut eval: impl FnMut(&FxPose) -> Evaluated) -> PfOutcome {
    let table = exp_table();
    let n = cfg.particles as usize;
    let mask = |s: u32| s & ((1 << SIGMA_BITS) - 1);
    let floor: [u32; PARAMS] = cfg.floor.map(mask);
    let cap: [u32; PARAMS] = std::array::from_fn(|d| mask(cfg.sigma0[d]).max(floor[d]));
    let mut sigma = cap;
    let mut centre = cfg.centre;
    let mut rng = Xorshift32::new(cfg.seed);
    let start = eval(&pose_of(&centre));
    let mut best = (start, centre);
    let mut particles = vec![[0i32; PARAMS]; n];
    let mut history = Vec::new();
    let mut iterations = 0;
    for k in 0..cfg.iterations {
        iterations = k + 1;
        let first = k == 0;
        let mut costs = Vec::with_capacity(n);
        let mut evals = Vec::with_capacity(n);
        for x in particles.iter_mut() {
            for d in 0..PARAMS {
                let u = rng.signed16() as i64;
                x[d] = propagate(x[d], centre[d], sigma[d], u, first, d == SCALE);
            }
            let e = eval(&pose_of(x));
            costs.push(e.cost);
            evals.push(e);
        }
        let (imin, cmin) =
            costs.iter().copied().enumerate().fold((0, u64::MAX), |a, (i, c)| if c < a.1 { (i, c) } else { a });
        let excess: Vec<u64> = costs.iter().map(|c| c - cmin).collect();
        let e = temper(&excess, cfg.temper_exp);
        let weights: Vec<u16> = excess.iter().map(|&x| weight(x, e, &table)).collect();
        let w_sum: u32 = weights.iter().map(|&w| w as u32).sum();
        if cmin < best.0.cost {
            best = (evals[imin], particles[imin]);
        }
        let mut estimate = [0i32; PARAMS];
        for d in 0..PARAMS {
            let s: i64 = particles
                .iter()
                .zip(&weights)
                .map(|(x, &w)| w as i64 * wrap24(x[d] as i64 - centre[d] as i64) as i64)
                .sum();
            estimate[d] = estimate_param(centre[d], s, w_sum, d == SCALE);
        }
        for d in 0..PARAMS {
            let dsum: u64 = particles
                .iter()
                .zip(&weights)
                .map(|(x, &w)| w as u64 * (wrap24(x[d] as i64 - estimate[d] as i64) as i64).unsigned_abs())
                .sum();
            sigma[d] = spread(dsum, w_sum, floor[d], cap[d]);
        }
        let estimate_eval = eval(&pose_of(&estimate));
        if estimate_eval.cost < best.0.cost {
            best = (estimate_eval, estimate);
        }
        centre = best.1;
        let mut record = IterationRecord {
            particles: particles.clone(),
            costs,
            temper: e,
            weights: weights.clone(),
            w_sum,
            estimate,
            estimate_eval,
            sigma,
            best_cost: best.0.cost,
            centre,
            resampled: Vec::new(),
        };
        let done = (best.0.cost <= cfg.thr_cost && best.0.max_d2 <= cfg.thr_max) || k + 1 == cfg.iterations;
        if !done {
            let picks = resample(&weights, w_sum, rng.unsigned16());
            particles = picks.iter().map(|&i| particles[i]).collect();
            record.resampled = particles.clone();
        }
        history.push(record);
        if done {
            break;
        }
    }
    PfOutcome { params: best.1, pose: pose_of(&best.1), best: best.0, iterations, start, history }
}

/// A small deterministic case for tests and examples: `n` points on a smooth 3-D curve
/// inside the unit ball (Q3.13), phase-shifted by `phase` and translated by `-shift` LSBs.
pub fn example_cloud(n: usize, shift: [i16; 3], phase: f64) -> Vec<crate::common::format::FxPoint> {
    (0..n)
        .map(|i| {
            let t = i as f64 * 0.37 + phase;
            let p = crate::common::format::point([0.6 * t.sin(), 0.5 * (1.7 * t).cos(), 0.4 * (0.5 * t).sin()]);
            [p[0] - shift[0], p[1] - shift[1], p[2] - shift[2]]
        })
        .collect()
}

/// `n` points of a smooth, asymmetric height field over a disc of radius 0.6 (golden-angle
/// sampling from `phase`), each less `shift` (LSB): a surface, so its normals are well
/// defined, for tests of the surface residual ([`crate::surface`]); `example_cloud` is a
/// space curve, whose normals are not.
pub fn example_surface(n: usize, shift: [i16; 3], phase: f64) -> Vec<crate::common::format::FxPoint> {
    (0..n)
        .map(|i| {
            let r = 0.6 * ((i as f64 + 0.5) / n as f64).sqrt();
            let a = i as f64 * 2.399_963 + phase;
            let (x, y) = (r * a.cos(), r * a.sin());
            let z = 0.06 * (9.0 * x).sin() * (7.0 * y + 0.4).cos() + 0.12 * x * y + 0.05 * y;
            let p = crate::common::format::point([x, y, z]);
            [p[0] - shift[0], p[1] - shift[1], p[2] - shift[2]]
        })
        .collect()
}

/// The configuration that goes with [`example_cloud`]: identity start, sigmas of 0.25 in
/// translation, 1.6% in scale, 1.4 degrees in angle, no thresholds.
pub fn example_config(particles: u16, iterations: u16, seed: u32) -> PfConfig {
    PfConfig {
        particles,
        iterations,
        temper_exp: 5,
        centre: [0, 0, 0, 1 << SCALE_FRAC, 0, 0, 0],
        sigma0: [1 << 17, 1 << 17, 1 << 17, 1 << 15, 1 << 16, 1 << 16, 1 << 16],
        floor: [1 << 10, 1 << 10, 1 << 10, 1 << 10, 1 << 9, 1 << 9, 1 << 9],
        seed,
        thr_cost: 0,
        thr_max: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::format::{MATRIX_FRAC, POSE_BITS};

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

    #[test]
    fn config_round_trips_and_checks() {
        let cfg = PfConfig {
            particles: 50,
            iterations: 40,
            temper_exp: 33,
            centre: [1, -2, 3, 1 << 21, -(1 << 23), 5, 6],
            sigma0: [100, 200, 300, 400, 500, 600, 700],
            floor: [1, 2, 3, 4, 5, 6, 7],
            seed: 0xdead_beef,
            thr_cost: (1 << 47) + 5,
            thr_max: (1 << 33) + 1,
        };
        let bytes = cfg.encode();
        assert_eq!(bytes.len(), RUN_BYTES);
        assert_eq!(PfConfig::decode(&bytes), Ok(cfg.clone()));
        assert_eq!(PfConfig::decode(&bytes[1..]), Err(ConfigError::Length(RUN_BYTES - 1)));
        let mut bad = bytes.clone();
        bad[0] = 0;
        bad[1] = 0;
        assert_eq!(PfConfig::decode(&bad), Err(ConfigError::Capacity(0, 40)));
    }

    #[test]
    fn resample_follows_the_weights() {
        let picks = resample(&[0, 65535, 0, 0], 65535, 1234);
        assert_eq!(picks, vec![1, 1, 1, 1]);
        // Pointers exactly on a CDF step stay (strictly beyond moves on, as in software).
        assert_eq!(resample(&[100, 100, 100, 100], 400, 0), vec![0, 0, 1, 2]);
        assert_eq!(resample(&[100, 100, 100, 100], 400, 1), vec![0, 1, 2, 3]);
        let picks = resample(&[300, 100, 0, 0], 400, 40000);
        assert_eq!(picks, vec![0, 0, 0, 1]);
    }

    #[test]
    fn temper_picks_the_median_bit_length() {
        // Excesses 0, 10, 100, 1000: rank 2 is 100, bitlen 7, so e = max(e_Q, 5, 5).
        assert_eq!(temper(&[0, 10, 100, 1000], 0), 5);
        assert_eq!(temper(&[0, 1 << 20, 1 << 30, 1 << 40], 0), 29);
        assert_eq!(temper(&[0, 1 << 20, 1 << 30, 1 << 40], 40), 40);
        assert_eq!(temper(&[0], 0), 5);
    }

    #[test]
    fn the_filter_finds_a_shifted_cloud() {
        // A small model and the same points shifted: the filter must bring the cost down.
        let model = crate::search::grid::Grid::build(&example_cloud(60, [0, 0, 0], 0.0)).unwrap();
        let shift = 400i16;
        let scan = example_cloud(60, [shift, 0, 0], 0.0);
        let cfg = example_config(24, 15, 7);
        let out = run(&cfg, |pose| evaluate(&model, &scan, pose));
        assert!(out.best.cost * 20 < out.start.cost, "{} vs {}", out.best.cost, out.start.cost);
        // The translation found is near +shift (in Q5.13 coordinates: 400 LSB).
        let t = translation(out.params[0]);
        assert!((t - shift as i32).abs() < 80, "t {t}");
        let again = run(&cfg, |pose| evaluate(&model, &scan, pose));
        assert_eq!(out, again);
    }
}
