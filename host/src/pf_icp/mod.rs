//! PF-ICP (Algorithm 6): k-means start, ICP covariance, SIR particle filter over the
//! 7 registration parameters, ICP polish; with a global search before the filter and a
//! conclusion after it (docs/global-registration.md).
//!
//! Stages (each timed in [`StageTimes`]), one module each below this one (with
//! [`kmeans`], the clustering, and [`hessian`], the cost curvature behind the covariance
//! the result reports):
//! 1. **Clustering and start** ([`crate::pf_icp::init`]): k-means on both clouds, paired centroids,
//!    SVD (Eq. 15); then the global search ([`crate::pf_icp::hypotheses`], with
//!    [`crate::pf_icp::features`]' proposals): the filter starts from its best hypothesis.
//! 2. **Covariance** ([`crate::pf_icp::covariance`], Algorithm 5): spread of ICP on `n_C`
//!    one-point-per-cluster subsets; its standard deviations set the propagation region
//!    (`+-2 sigma`), the variance of the subset MSDs is `Q`.
//! 3. **Filter** ([`crate::pf_icp::particle_filter`]): particles `[a, b, c, s, phi, theta, psi]`
//!    in the centred frame ([`Centred`]: rotation about the clouds' centroids), each
//!    weighed by the capped surface cost ([`Surface::cost`]) of the transformed scan (a
//!    fixed random subset of at most `filter_points` scan points); after every iteration a
//!    few trimmed ICP iterations refine the weighted estimate and the best particle
//!    (`icp_per_iteration`, 0 to turn off); stop on the thresholds, a stalled best cost
//!    (`patience`) or the cap.
//! 4. **Polish and conclusion** ([`crate::pf_icp::conclusion`]): point-to-plane ICP with scale
//!    (`polish_iterations`) on the whole scan from the filter's estimate and the best
//!    hypotheses, the lowest cost wins; alternatives, covariance, fit.
//!
//! [`register_with`] takes the particles' costs and weights from a [`ParticleWeights`]
//! source instead (the board: `crate::board::host_driven`); everything else is the same.

pub mod conclusion;
pub mod covariance;
pub mod evidence;
pub mod features;
pub mod hessian;
pub mod hypotheses;
pub mod init;
pub mod kmeans;
pub mod objective;
pub mod particle_filter;
pub mod probe;
pub mod rescue;
pub mod surface;
pub mod symmetry;
pub mod verdict;

use crate::geometry::{Centred, Params, Pose, ScaleBounds};
use crate::nn::NearestNeighbours;
use crate::pf_icp::conclusion::Conclusion;
use crate::pf_icp::covariance::{approximate_icp_variance, IcpCovariance};
use crate::pf_icp::init::{initial_pose_for, InitMode, InitialPose};
use crate::pf_icp::kmeans::Pairing;
use crate::pf_icp::surface::Surface;
use crate::registration::icp::{IcpSettings, Registration};
use evidence::Evidence;
use hypotheses::{Hypothesis, SearchSettings};
use nalgebra::Point3;
pub use objective::ParticleWeights;
use objective::PoseObjective;
use particle_filter::{Adaptive, FilterSettings, WeighError};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::time::{Duration, Instant};

/// Most particles the software filter takes (memory: a particle is 7 numbers and a cost).
pub const MAX_FILTER_PARTICLES: usize = 100_000;
/// Most filter iterations.
pub const MAX_ITERATIONS: usize = 100_000;
/// Most clusters per cloud.
pub const MAX_CLUSTERS: usize = 100_000;

/// A registration is *large* when either cloud has more points than this ([`is_large`]).
/// At or below it every stage runs on every point exactly as before (the published
/// benchmark figures hold bit for bit); above it the stages whose cost grows with the
/// clouds work on bounded, seeded subsets:
/// - k-means on at most [`KMEANS_POINTS`] points of each cloud, every point then assigned
///   to its nearest centroid ([`kmeans::kmeans_sampled`]);
/// - the search, the covariance, the filter and the polish and comparison of the final
///   candidates against a seeded random subset of at most [`SEARCH_MODEL_POINTS`] model
///   points (its own normals and spacing: [`search_model`]), the candidates on at most
///   [`conclusion::LARGE_COMPARE_POINTS`] scan points;
/// - the winner's final polish against the whole model on at most
///   [`conclusion::FINAL_POLISH_POINTS`] scan points and
///   [`conclusion::FINAL_POLISH_ITERATIONS`] iterations;
/// - the scan's noise from at most [`NOISE_POINTS`] of its points, the model's spacing
///   from at most [`surface::SPACING_POINTS`] of its points, its normals as scan points
///   first land next to them.
///
/// The uncertainty, the fit and the MSD still take every scan point (one pass each, so
/// that a larger scan still narrows the uncertainty).
pub const LARGE_CLOUD: usize = 20_000;
/// In a large registration: points of each cloud k-means runs on.
pub const KMEANS_POINTS: usize = 3_000;
/// In a large registration: model points the search, the covariance, the filter and the
/// comparison of the final candidates run on. (The k-d tree's queries from poses far from
/// the answer cost more the denser the model: on model-1 the filter took 1.5 s against
/// 200,000 model points, 0.12 s against 3,000.)
pub const SEARCH_MODEL_POINTS: usize = 5_000;
/// Seed offset of the search's model subset.
const SEARCH_MODEL_SEED: u64 = 0x7365_6172_6368;
/// In a large registration: scan points the scan's noise is estimated from
/// ([`evidence::scan_noise`]). A denser scan's ten nearest neighbours span little more than
/// its noise, and the estimate shrank with the density (model-1, noise 0.01: 99.8% of a
/// 15,000-point scan explained within 3 sigmas, 80% of a 100,000-point one, 33% of
/// 500,000); on a subset as large as a small registration's scan it does not.
pub const NOISE_POINTS: usize = 20_000;
/// Seed offset of the noise estimate's scan subset.
const NOISE_SEED: u64 = 0x006e_6f69_7365;

/// Whether a registration of a `scan_points` scan to a `model_points` model takes the
/// large-cloud path ([`LARGE_CLOUD`]).
pub fn is_large(model_points: usize, scan_points: usize) -> bool {
    model_points.max(scan_points) > LARGE_CLOUD
}

/// The scan points the scan's noise is estimated from: in a large registration a random
/// subset (drawn with `seed`) of at most [`NOISE_POINTS`]; the whole scan otherwise.
fn noise_points<'a>(scan: &'a [Point3<f64>], model_points: usize, seed: u64) -> std::borrow::Cow<'a, [Point3<f64>]> {
    if !is_large(model_points, scan.len()) || scan.len() <= NOISE_POINTS {
        return std::borrow::Cow::Borrowed(scan);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ NOISE_SEED);
    let mut idx = rand::seq::index::sample(&mut rng, scan.len(), NOISE_POINTS).into_vec();
    idx.sort_unstable();
    std::borrow::Cow::Owned(idx.iter().map(|&i| scan[i]).collect())
}

/// The model the search and the filter run on in a large registration: a random subset
/// (drawn with `seed`, in the model's order) of at most [`SEARCH_MODEL_POINTS`] of its
/// points; `None` (the whole model) otherwise.
pub fn search_model(model: &[Point3<f64>], scan_points: usize, seed: u64) -> Option<NearestNeighbours> {
    if !is_large(model.len(), scan_points) || model.len() <= SEARCH_MODEL_POINTS {
        return None;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ SEARCH_MODEL_SEED);
    let mut idx = rand::seq::index::sample(&mut rng, model.len(), SEARCH_MODEL_POINTS).into_vec();
    idx.sort_unstable();
    let subset: Vec<Point3<f64>> = idx.iter().map(|&i| model[i]).collect();
    Some(NearestNeighbours::new(&subset))
}

/// PF-ICP settings.
#[derive(Clone, Debug)]
pub struct PfIcpSettings {
    /// Clusters `K` per cloud (clamped to a tenth of the smaller cloud, at least 3).
    pub clusters: usize,
    /// Particles `n_p`.
    pub particles: usize,
    /// Filter iteration cap.
    pub iterations: usize,
    /// Subsets `n_C` for the covariance.
    pub covariance_subsets: usize,
    /// Seed of every random choice.
    pub seed: u64,
    /// Cluster pairing for the start.
    pub init: InitMode,
    /// Propagation region half-width in sigmas (the paper's 2).
    pub region_sigmas: f64,
    /// Scan points of the weight sample (a fixed random subset in random order; all if
    /// fewer): the search ranks its hypotheses on it, the board weighs its particles on it.
    pub weight_points: usize,
    /// Scan points the host's filter weighs each particle and refines over: the first of the
    /// weight sample (the polish after the filter sets the accuracy; docs/benchmarks.md,
    /// "Time and large clouds").
    pub filter_points: usize,
    /// ICP iterations run on the estimate after every filter iteration (0: none).
    pub icp_per_iteration: usize,
    /// Iterations of the final point-to-plane polish on the whole scan (0: none).
    pub polish_iterations: usize,
    /// Stop when the average closest-point distance is below this fraction of the
    /// model's bounding-box diagonal ...
    pub threshold_avg: f64,
    /// ... and the maximum is below this fraction.
    pub threshold_max: f64,
    /// Optional particle-count adaptation.
    pub adaptive: Option<Adaptive>,
    /// Stop the filter when its best cost stalls this many iterations
    /// ([`FilterSettings::patience`]; `None`: thresholds and cap only).
    pub patience: Option<usize>,
    /// The global search for the start ([`crate::pf_icp::hypotheses`]); `None`: the k-means start
    /// alone, as in the paper.
    pub search: Option<SearchSettings>,
    /// What is known of the scale (`--scale`, `--scale-range`): every stage keeps the scale
    /// inside; a fixed scale is no parameter of the filter, the polish or the covariance.
    pub scale: ScaleBounds,
    /// Where the sensor was, in the scan's frame (`--viewpoint`), if known.
    pub viewpoint: Option<Point3<f64>>,
}

impl Default for PfIcpSettings {
    fn default() -> Self {
        Self {
            clusters: 100,
            particles: 50,
            iterations: 50,
            covariance_subsets: 30,
            seed: 1,
            init: InitMode::Auto,
            region_sigmas: 2.0,
            weight_points: 1000,
            filter_points: 500,
            icp_per_iteration: 2,
            polish_iterations: 50,
            threshold_avg: 1e-4,
            threshold_max: 1e-3,
            adaptive: None,
            patience: Some(8),
            search: Some(SearchSettings::default()),
            scale: ScaleBounds::FREE,
            viewpoint: None,
        }
    }
}

/// Wall time of each stage.
#[derive(Clone, Copy, Debug, Default)]
pub struct StageTimes {
    /// k-means and the start.
    pub clustering: Duration,
    /// Algorithm 5.
    pub covariance: Duration,
    /// The particle filter.
    pub filter: Duration,
    /// The final ICP.
    pub polish: Duration,
    /// The rescue's wider search and second conclusion (zero when it did not run).
    pub rescue: Duration,
}

/// Everything PF-ICP produces.
#[derive(Clone, Debug)]
pub struct PfIcpResult {
    /// Pose, MSD over the whole scan, filter iterations, cost per filter iteration.
    pub registration: Registration,
    /// The k-means start.
    pub initial: InitialPose,
    /// The distinct hypotheses of the global search, best first (empty without it).
    pub hypotheses: Vec<Hypothesis>,
    /// The covariance estimate.
    pub covariance: IcpCovariance,
    /// The polish, the choice among the hypotheses, alternatives, uncertainty and fit.
    pub conclusion: Conclusion,
    /// The filter's own estimate, before the polish.
    pub filter_pose: Pose,
    /// Stage timings.
    pub times: StageTimes,
    /// The filter's per-iteration records.
    pub filter_history: Vec<crate::pf_icp::particle_filter::IterationRecord>,
    /// The filter's estimate after each iteration as a pose (one per `filter_history`
    /// record; empty where there is no history).
    pub filter_poses: Vec<Pose>,
}

/// The filter's scale stays within these factors of its start's.
const SCALE_BOUNDS: (f64, f64) = (0.5, 2.0);

/// Smallest sigma per parameter: 0.05% of the diagonal, 0.05% of scale, 0.02 degree.
fn sigma_floor(diag: f64, scale: f64) -> Vec<f64> {
    let t = 5e-4 * diag;
    let a = 0.02f64.to_radians();
    vec![t, t, t, 5e-4 * scale, a, a, a]
}

/// Largest initial sigma: a quarter of the diagonal, 20% of scale, 30 degrees.
fn sigma_cap(diag: f64, scale: f64) -> Params {
    let t = 0.25 * diag;
    let a = 30f64.to_radians();
    [t, t, t, 0.2 * scale, a, a, a]
}

/// Smallest initial sigma for a start from `pairing`: ICP on one-point-per-cluster subsets
/// agrees with itself even when the start sits in a wrong basin nearby, so the region is
/// never narrower than the start's own accuracy. Index pairing is exact up to noise (0.5%
/// of the diagonal, 0.5% scale, 1 degree); the geometric start is good to a few degrees
/// (2% of the diagonal, 2% scale, 5 degrees).
fn start_prior(pairing: Pairing, diag: f64, scale: f64) -> Params {
    let (t, s, a) = match pairing {
        Pairing::Index => (5e-3, 5e-3, 1.0),
        Pairing::Nearest => (2e-2, 2e-2, 5.0),
    };
    let a = f64::to_radians(a);
    [t * diag, t * diag, t * diag, s * scale, a, a, a]
}

/// Register `scan` to the model behind `nn` with PF-ICP.
pub fn register(nn: &NearestNeighbours, scan: &[Point3<f64>], settings: &PfIcpSettings) -> PfIcpResult {
    register_with(nn, scan, settings, None).unwrap_or_else(|e| panic!("software particle weights failed: {e}"))
}

/// The fixed random subset of the scan the particle costs are taken over (at most
/// `settings.weight_points` points, drawn with the seed, in random order).
pub fn weight_sample(scan: &[Point3<f64>], settings: &PfIcpSettings) -> Vec<Point3<f64>> {
    // Always in random order, even when every point is taken: the search takes its small
    // subsets as prefixes, and a scan in file order (scan lines, a sorted view) would give
    // it a slab at one end.
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    scan.choose_multiple(&mut rng, settings.weight_points.min(scan.len())).copied().collect()
}

/// Everything PF-ICP computes before its filter (stages 1 and 2): the weight sample, the
/// start, the covariance and the filter's prior in the centred frame. The on-board filter
/// (`crate::board::on_board::register_on_board`) takes it from here without running the host's.
#[derive(Clone, Debug)]
pub struct Prior {
    /// The scan points the particle costs are taken over ([`weight_sample`]).
    pub sample: Vec<Point3<f64>>,
    /// The k-means start.
    pub initial: InitialPose,
    /// The distinct hypotheses of the global search, best first (empty without it).
    pub hypotheses: Vec<Hypothesis>,
    /// The filter's start: the best hypothesis, or the k-means start without the search.
    pub start: Pose,
    /// The covariance estimate.
    pub covariance: IcpCovariance,
    /// The centred frame the filter's states live in (the clouds' centroids).
    pub frame: Centred,
    /// The start in that frame: the filter's first centre.
    pub init_params: Params,
    /// Initial sigma per state (also the cap of the region update).
    pub sigma0: Vec<f64>,
    /// Smallest sigma per state.
    pub floor: Vec<f64>,
    /// The likelihood's `Q` (the variance of the subset MSDs).
    pub q: f64,
    /// Stop threshold on the average closest-point distance [units].
    pub threshold_avg: f64,
    /// Stop threshold on the largest closest-point distance [units].
    pub threshold_max: f64,
    /// The model's bounding-box diagonal.
    pub diag: f64,
    /// The scan's own evidence (noise, caps, viewpoint) the poses are ranked by.
    pub evidence: Evidence,
    /// Wall time of the clustering and the start.
    pub clustering_time: Duration,
    /// Wall time of the covariance.
    pub covariance_time: Duration,
}

/// Stages 1 and 2 of PF-ICP: the start (k-means), the covariance and the filter's prior.
/// In a large registration ([`is_large`]) everything but the clustering runs against the
/// model's search subset ([`search_model`]).
pub fn prior(nn: &NearestNeighbours, scan: &[Point3<f64>], settings: &PfIcpSettings) -> Prior {
    match search_model(nn.points(), scan.len(), settings.seed) {
        Some(subset) => prior_on(&Surface::new(&subset), nn.points(), scan, settings),
        None => prior_on(&Surface::new(nn), nn.points(), scan, settings),
    }
}

/// [`prior`] against `surface`, the [`Surface`] of `whole` (the model) or of its search
/// subset; the clusters are the whole model's.
fn prior_on(surface: &Surface, whole: &[Point3<f64>], scan: &[Point3<f64>], settings: &PfIcpSettings) -> Prior {
    let nn = surface.nn();
    let model = nn.points();
    let diag = crate::cloud::bbox_diagonal(model);
    let sample = weight_sample(scan, settings);
    let k = settings.clusters.min(scan.len().min(whole.len()) / 10).max(3);

    let t0 = Instant::now();
    let bounds = &settings.scale;
    let evidence = Evidence::new(
        surface,
        &noise_points(scan, whole.len(), settings.seed),
        bounds.clamp(hypotheses::radius_ratio(scan, model)),
        settings.viewpoint,
    );
    let initial = initial_pose_for(nn, whole, scan, &sample, k, settings.seed, settings.init, bounds);
    let hypotheses = match &settings.search {
        Some(search) => global_search(surface, scan, &sample, &initial, search, settings, &evidence),
        None => Vec::new(),
    };
    let start = hypotheses.first().map_or(initial.pose, |h| h.pose);
    // A start other than the k-means one is as good as the geometric pairing's.
    let pairing = if start == initial.pose { initial.pairing } else { Pairing::Nearest };
    let t1 = Instant::now();
    let cov_settings = IcpSettings { max_iterations: 30, scale_bounds: *bounds, ..Default::default() };
    let covariance = approximate_icp_variance(
        nn,
        scan,
        &initial.scan_clusters,
        &start,
        settings.covariance_subsets,
        settings.seed,
        &cov_settings,
    );
    let t2 = Instant::now();

    let frame = Centred { scan: crate::cloud::centroid(scan), model: crate::cloud::centroid(model) };
    let init_params = frame.params(&start);
    let (_, variance) = covariance.stats_in(&frame, &start);
    let cap = sigma_cap(diag, start.scale);
    let floor = sigma_floor(diag, start.scale);
    let least = start_prior(pairing, diag, start.scale);
    let mut sigma0: Vec<f64> =
        variance.iter().enumerate().map(|(d, v)| v.sqrt().max(least[d]).max(floor[d]).min(cap[d])).collect();
    let mut floor = floor;
    if bounds.fixed_value().is_some() {
        // The scale is no parameter of the filter.
        sigma0[3] = 0.0;
        floor[3] = 0.0;
    }
    let q = covariance.msd_variance;
    Prior {
        sample,
        initial,
        hypotheses,
        start,
        covariance,
        frame,
        init_params,
        sigma0,
        floor,
        q,
        threshold_avg: settings.threshold_avg * diag,
        threshold_max: settings.threshold_max * diag,
        diag,
        evidence,
        clustering_time: t1 - t0,
        covariance_time: t2 - t1,
    }
}

/// The global search ([`hypotheses::search`]) with `search`'s settings from every start:
/// the k-means stage's candidates, the uniform rotations, the sensor's view of each when
/// its position is known, and the feature proposals; the k-means start itself is ranked
/// unrefined.
pub(crate) fn global_search(
    surface: &Surface,
    scan: &[Point3<f64>],
    sample: &[Point3<f64>],
    initial: &InitialPose,
    search: &SearchSettings,
    settings: &PfIcpSettings,
    evidence: &Evidence,
) -> Vec<Hypothesis> {
    let nn = surface.nn();
    let model = nn.points();
    let bounds = &settings.scale;
    let mut starts = initial.candidates.clone();
    starts.extend(hypotheses::grid_starts(scan, model, search.grid, bounds));
    if let Some(v) = &settings.viewpoint {
        starts.extend(hypotheses::view_starts(surface, sample, search.grid, bounds, v));
    }
    starts.extend(crate::pf_icp::features::proposals(
        nn,
        sample,
        hypotheses::radius_ratio(scan, model),
        settings.seed,
        bounds,
    ));
    hypotheses::search(surface, sample, &[initial.pose], &starts, search, bounds, evidence)
}

/// [`register`] with the particles' costs and weights from `weights` (`None`: the host's
/// own, exactly as [`register`]). Stops at the first error of the source.
pub fn register_with(
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
    weights: Option<&dyn ParticleWeights>,
) -> Result<PfIcpResult, WeighError> {
    let surface = Surface::new(nn);
    // In a large registration the search, the filter and the comparison of the candidates
    // run against the model's search subset.
    let subset = search_model(nn.points(), scan.len(), settings.seed);
    let subset_surface = subset.as_ref().map(Surface::new);
    let search = subset_surface.as_ref().unwrap_or(&surface);
    let Prior {
        sample,
        initial,
        hypotheses,
        covariance,
        frame,
        init_params,
        sigma0,
        floor,
        q,
        threshold_avg,
        threshold_max,
        diag,
        evidence,
        clustering_time,
        covariance_time,
        ..
    } = prior_on(search, nn.points(), scan, settings);
    let t2 = Instant::now();
    if let Some(source) = weights {
        source.prepare(&sample)?;
    }
    let start_scale = frame.pose(&init_params).scale;
    let objective = PoseObjective {
        // (The board's costs are over the whole model.)
        surface: if weights.is_some() { &surface } else { search },
        // (The board weighs the whole weight sample.)
        sample: if weights.is_some() { &sample } else { &sample[..settings.filter_points.max(1).min(sample.len())] },
        frame,
        refine_iterations: settings.icp_per_iteration,
        weights,
        cap: crate::pf_icp::surface::COST_CAP * diag,
        scale_range: {
            let b = settings.scale.within(start_scale * SCALE_BOUNDS.0, start_scale * SCALE_BOUNDS.1);
            (b.lo, b.hi)
        },
        bounds: settings.scale,
    };
    let filter_settings = FilterSettings {
        particles: settings.particles,
        iterations: settings.iterations,
        region_sigmas: settings.region_sigmas,
        q,
        sigma_floor: floor,
        threshold_avg,
        threshold_max,
        adaptive: settings.adaptive,
        patience: settings.patience,
        seed: settings.seed.wrapping_add(1),
    };
    let filtered = particle_filter::try_run(&objective, &init_params, &sigma0, &filter_settings)?;
    let filter_pose = frame.pose(filtered.estimate.as_slice().try_into().expect("7 states"));
    let t3 = Instant::now();

    // The answer's own checks against the whole model (its spacing, not the subset's).
    let full_evidence = match subset {
        Some(_) => Evidence::new(
            &surface,
            &noise_points(scan, nn.points().len(), settings.seed),
            settings.scale.clamp(hypotheses::radius_ratio(scan, nn.points())),
            settings.viewpoint,
        ),
        None => evidence,
    };
    let conclude = |hypotheses: &[Hypothesis]| {
        crate::pf_icp::conclusion::conclude_on(
            search,
            &evidence,
            &surface,
            &full_evidence,
            scan,
            &filter_pose,
            hypotheses,
            settings.polish_iterations,
            &settings.scale,
        )
    };
    let first = conclude(&hypotheses);
    let (conclusion, hypotheses, rescue_time) =
        rescue::conclude_or_rescue(first, hypotheses, conclude, search, scan, &sample, &initial, settings, &evidence);
    let polished = Registration {
        pose: conclusion.pose,
        msd: crate::registration::icp::msd(nn, scan, &conclusion.pose),
        iterations: filtered.iterations,
        errors: Vec::new(),
    };
    let t4 = Instant::now();
    let mut errors: Vec<f64> = filtered.history.iter().map(|h| h.cost).collect();
    errors.push(polished.msd);
    Ok(PfIcpResult {
        registration: Registration { pose: polished.pose, msd: polished.msd, iterations: filtered.iterations, errors },
        initial,
        hypotheses,
        conclusion,
        covariance,
        filter_pose,
        filter_poses: filtered
            .history
            .iter()
            .filter_map(|h| <&Params>::try_from(h.estimate.as_slice()).ok().map(|p| frame.pose(p)))
            .collect(),
        filter_history: filtered.history.clone(),
        times: StageTimes {
            clustering: clustering_time,
            covariance: covariance_time,
            filter: t3 - t2,
            polish: t4 - t3 - rescue_time,
            rescue: rescue_time,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::datasets::{make, ModelId, Sampling, ScanSpec};

    #[test]
    fn same_seed_same_pose() {
        let id = ModelId::Model2;
        let ds = make(
            id,
            600,
            &id.table1_truth(),
            &ScanSpec { sampling: Sampling::Independent { points: 500 }, noise: 0.0, seed: 4 },
        );
        let nn = NearestNeighbours::new(&ds.model);
        let s = PfIcpSettings { clusters: 30, particles: 20, iterations: 8, ..Default::default() };
        let a = register(&nn, &ds.scan, &s);
        let b = register(&nn, &ds.scan, &s);
        assert_eq!(a.registration.pose, b.registration.pose);
        assert_eq!(a.registration.errors, b.registration.errors);
    }
}
