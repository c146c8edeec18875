//! The cycle-accurate reference of the particle-filter sequencer
//! (`rtl::board::sequencer::PfSequencer`, docs/sequencer.md): its ports, and
//! [`SequencerModel`], register for register the RTL, whose datapath results are those of
//! the functional reference [`crate::pf::run`].

use crate::format::FxPose;

/// Input ports (before an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SeqInputs {
    /// Synchronous reset.
    pub reset: bool,
    /// Configuration write.
    pub cfg_we: bool,
    /// Configuration word address (5 bits).
    pub cfg_addr: u8,
    /// Configuration word (48 bits).
    pub cfg_data: u64,
    /// Start a run.
    pub go: bool,
    /// The pipeline may be started.
    pub nn_ready: bool,
    /// The pipeline's cost is presented.
    pub cost_valid: bool,
    /// The cost (48 bits).
    pub cost: u64,
    /// A nearest-neighbour result is presented.
    pub nn_valid: bool,
    /// Its squared distance (34 bits).
    pub nn_dist: u64,
}

/// Output ports (after an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SeqOutputs {
    /// Start the pipeline (one clock).
    pub start: bool,
    /// The pose (216 bits, [`FxPose::pack`]).
    pub pose: [u64; 4],
    /// A run is in progress.
    pub running: bool,
    /// A run has finished.
    pub finished: bool,
    /// Iterations completed.
    pub iterations: u16,
    /// Best cost so far.
    pub best_cost: u64,
    /// Its largest squared distance.
    pub best_max: u64,
    /// The best parameters, 24 bits each from bit 0 (168 bits).
    pub params: [u64; 3],
    /// Particle RAM write enable.
    pub p_we: bool,
    /// Its address `{half, particle, parameter}` (12 bits).
    pub p_waddr: u16,
    /// Its data (24 bits).
    pub p_wdata: u32,
}

/// The configuration writes that load a [`crate::pf::PfConfig`] (word address, 48-bit word),
/// in the order the board's engine writes them.
pub fn config_writes(cfg: &crate::pf::PfConfig) -> Vec<(u8, u64)> {
    let mut w: Vec<(u8, u64)> = Vec::with_capacity(25);
    for d in 0..crate::pf::PARAMS {
        w.push((d as u8, cfg.centre[d] as u32 as u64 & 0xff_ffff));
    }
    for d in 0..crate::pf::PARAMS {
        w.push((7 + d as u8, cfg.sigma0[d] as u64));
    }
    for d in 0..crate::pf::PARAMS {
        w.push((14 + d as u8, cfg.floor[d] as u64));
    }
    w.push((21, cfg.seed as u64));
    w.push((22, cfg.thr_cost));
    w.push((23, cfg.thr_max));
    w.push((24, cfg.particles as u64 | (cfg.iterations as u64) << 16 | (cfg.temper_exp as u64 & 63) << 32));
    w
}

/// The pose of a packed 216-bit pose word.
pub fn unpack_pose(w: &[u64; 4]) -> FxPose {
    let field = |k: usize| -> i32 {
        let at = 18 * k;
        let (word, off) = (at / 64, at % 64);
        let mut raw = w[word] >> off;
        if off + 18 > 64 {
            raw |= w[word + 1] << (64 - off);
        }
        (((raw & 0x3_ffff) << 46) as i64 >> 46) as i32
    };
    FxPose { m: std::array::from_fn(field), t: std::array::from_fn(|k| field(9 + k)) }
}
