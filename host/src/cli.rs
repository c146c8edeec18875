//! Output formatting shared by the `pficp` subcommands.

use crate::geometry::{Pose, PoseRecord};
use crate::registration::icp::Registration;
use serde::Serialize;

/// The JSON object `pficp register --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct RegisterReport {
    /// Method name.
    pub method: String,
    /// Where the particle filter ran: `software` (the host), `board` (the filter on the
    /// board) or `board-host-driven` (the host's filter, the particles weighed on the board).
    pub engine: String,
    /// The board's serial port when `engine` is `board` or `board-host-driven`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub port: Option<String>,
    /// Scale factor.
    pub scale: f64,
    /// Rotation, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Translation.
    pub translation: [f64; 3],
    /// `[phi, theta, psi]` in degrees.
    pub euler_deg: [f64; 3],
    /// The 4x4 matrix `[[sR, T], [0, 1]]`, row-major.
    pub matrix: [[f64; 4]; 4],
    /// Mean squared closest-point distance over the whole scan.
    pub msd: f64,
    /// Iterations.
    pub iterations: usize,
    /// Wall time [s].
    pub seconds: f64,
    /// PF-ICP only: what the result says about itself.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub assessment: Option<Assessment>,
    /// What produced the result: the inputs, the settings and the command that runs it
    /// again (`pficp register` sets it).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
}

/// The inputs and settings of a registration, enough to run it again (JSON keys
/// `version`, `inputs`, `settings`, `command`).
#[derive(Clone, Debug, Serialize)]
pub struct Provenance {
    /// The `pficp` version that produced the result.
    pub version: &'static str,
    /// The clouds as given and their sizes.
    pub inputs: Inputs,
    /// The method's settings.
    pub settings: Settings,
    /// The `pficp register` command with every setting spelled out (paths as given).
    pub command: String,
}

/// The two clouds of a registration.
#[derive(Clone, Debug, Serialize)]
pub struct Inputs {
    /// Model file, as given.
    pub model: String,
    /// Scan file, as given.
    pub scan: String,
    /// Points read from the model file.
    pub model_points: usize,
    /// Points read from the scan file.
    pub scan_points: usize,
}

/// The settings that decide a registration's result.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    /// Seed of every random choice.
    pub seed: u64,
    /// Clusters K per cloud (PF-ICP).
    pub clusters: usize,
    /// Particles (PF-ICP).
    pub particles: usize,
    /// Iteration cap.
    pub iterations: usize,
    /// PF-ICP's cluster pairing (`auto`, `index`, `nearest`).
    pub init: String,
    /// The fixed scale (`--scale`), or `null`.
    pub scale: Option<f64>,
    /// The scale's bounds `[lo, hi]` (`--scale-range`), or `null`.
    pub scale_range: Option<[f64; 2]>,
    /// The sensor's position in the scan's frame (`--viewpoint`), or `null`.
    pub viewpoint: Option<[f64; 3]>,
    /// Whether a ruled-out answer gets the rescue search (`false`: `--no-rescue`).
    pub rescue: bool,
    /// With the filter on the board: scan points it weighs each particle over.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub board_points: Option<usize>,
}

impl Settings {
    /// What `request` ran with.
    pub fn of(request: &crate::request::Request) -> Settings {
        let s = &request.settings;
        Settings {
            seed: s.seed,
            clusters: s.clusters,
            particles: s.particles,
            iterations: s.iterations,
            init: s.init.name().to_string(),
            scale: s.scale.fixed_value(),
            scale_range: (!s.scale.is_free() && s.scale.fixed_value().is_none()).then_some([s.scale.lo, s.scale.hi]),
            viewpoint: s.viewpoint.map(|v| [v.x, v.y, v.z]),
            rescue: s.search.as_ref().is_some_and(|s| s.rescue),
            board_points: match request.engine {
                crate::request::Engine::OnBoard { board_points, .. } => Some(board_points),
                _ => None,
            },
        }
    }
}

impl Provenance {
    /// From the inputs and settings; `command` is built from them (`port` for a board run,
    /// `host_driven` for its host-driven mode).
    pub fn new(method: &str, inputs: Inputs, settings: Settings, port: Option<&str>, host_driven: bool) -> Self {
        let mut words = vec![
            "pficp".to_string(),
            "register".to_string(),
            "--model".to_string(),
            shell_word(&inputs.model),
            "--scan".to_string(),
            shell_word(&inputs.scan),
            "--method".to_string(),
            method.to_string(),
        ];
        for (flag, value) in [
            ("--clusters", settings.clusters.to_string()),
            ("--particles", settings.particles.to_string()),
            ("--iterations", settings.iterations.to_string()),
            ("--seed", settings.seed.to_string()),
            ("--init", settings.init.to_string()),
        ] {
            words.push(flag.to_string());
            words.push(value);
        }
        let join = |v: &[f64]| v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(",");
        if let Some(s) = settings.scale {
            words.extend(["--scale".to_string(), format!("{s:?}")]);
        }
        if let Some(r) = settings.scale_range {
            words.extend(["--scale-range".to_string(), join(&r)]);
        }
        if let Some(v) = settings.viewpoint {
            words.extend(["--viewpoint".to_string(), join(&v)]);
        }
        if !settings.rescue {
            words.push("--no-rescue".to_string());
        }
        if let Some(port) = port {
            words.push("--board".to_string());
            words.push(shell_word(port));
            if host_driven {
                words.push("--host-driven".to_string());
            }
        }
        if let Some(n) = settings.board_points {
            words.push("--board-points".to_string());
            words.push(n.to_string());
        }
        Provenance { version: env!("CARGO_PKG_VERSION"), inputs, settings, command: words.join(" ") }
    }
}

/// `s` quoted for a POSIX shell where it needs quoting.
fn shell_word(s: &str) -> String {
    let plain = !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "/._-+,:=@%".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// Another pose the scan does not rule out (JSON).
#[derive(Clone, Debug, Serialize)]
pub struct AlternativeRecord {
    /// The pose.
    #[serde(flatten)]
    pub pose: PoseRecord,
    /// Its capped surface cost over the whole scan.
    pub cost: f64,
    /// Its mean cost excess over the answer, in standard errors.
    pub excess_sigmas: f64,
    /// It fits as well as the answer within the noise; `false`: it fits worse, but the
    /// evidence rules do not rule it out (listed only beside some that fit as well).
    pub fits_as_well: bool,
}

/// PF-ICP's verdict, alternatives, uncertainty and fit (docs in `crate::pf_icp::conclusion`
/// and `crate::pf_icp::verdict`).
#[derive(Clone, Debug, Serialize)]
pub struct Assessment {
    /// `confident` (act on the pose), `ambiguous` (the answer and its alternatives fit as
    /// well) or `unreliable` (do not act on it).
    pub verdict: crate::pf_icp::verdict::Verdict,
    /// The verdict's reasons in words (empty for `confident`).
    pub reasons: Vec<String>,
    /// What the verdict was judged on: `explained` (share of the scan on the surface within
    /// the noise), `hidden` (share the model would hide from `--viewpoint`, or `null`),
    /// `scale_at_bound`, `alternatives` (how many fit as well), `not_ruled_out` (how many more
    /// are listed), `undetermined`, `widest_sigma` (deg, fraction of the diagonal, relative
    /// scale).
    pub checks: crate::pf_icp::verdict::Checks,
    /// Other poses that fit as well within the noise, then (only beside some of those) the
    /// poses that fit worse but are not ruled out; empty: the pose is unambiguous.
    pub alternatives: Vec<AlternativeRecord>,
    /// Names and order of the covariance's parameters ([`crate::pf_icp::surface::LOCAL_NAMES`]).
    pub covariance_order: [&'static str; 7],
    /// Covariance (model units, scale, rad); `null` for undetermined parameters.
    pub covariance: [[Option<f64>; 7]; 7],
    /// One-sigma values in that order (`null`: undetermined).
    pub sigma: [Option<f64>; 7],
    /// Motions the scan cannot determine (a collinear or planar scan): parameter names, or
    /// `translation along (x, y, z)` and the like for oblique ones.
    pub undetermined: Vec<String>,
    /// Fraction of scan points within `inlier_distance` of the model's surface (as Open3D's
    /// fitness, on the surface distance).
    pub fitness: f64,
    /// RMS distance of those points.
    pub inlier_rmse: f64,
    /// The inlier distance (2% of the model's diagonal).
    pub inlier_distance: f64,
    /// Capped surface cost of the pose over the whole scan.
    pub cost: f64,
    /// The rescue search ran: the evidence ruled out the first search's answer, and this
    /// result is the better of both searches' ([`crate::pf_icp::rescue`]).
    pub rescued: bool,
}

impl Assessment {
    /// From PF-ICP's conclusion.
    pub fn new(c: &crate::pf_icp::conclusion::Conclusion) -> Self {
        Assessment {
            verdict: c.verdict,
            reasons: c.reasons.clone(),
            checks: c.checks.clone(),
            alternatives: c
                .alternatives
                .iter()
                .map(|a| AlternativeRecord {
                    pose: a.pose.record(),
                    cost: a.cost,
                    excess_sigmas: a.excess_sigmas,
                    fits_as_well: a.fits_as_well,
                })
                .collect(),
            covariance_order: crate::pf_icp::surface::LOCAL_NAMES,
            covariance: c.uncertainty.covariance,
            sigma: c.uncertainty.sigma,
            undetermined: c.uncertainty.undetermined.clone(),
            fitness: c.fit.fitness,
            inlier_rmse: c.fit.inlier_rmse,
            inlier_distance: c.fit.inlier_distance,
            cost: c.fit.cost,
            rescued: false,
        }
    }

    /// The verdict line: the verdict and its reasons.
    pub fn verdict_line(&self) -> String {
        let mut s = format!("verdict      {}", self.verdict.name());
        if !self.reasons.is_empty() {
            s += &format!(": {}", self.reasons.join("; "));
        }
        s + "\n"
    }

    /// The text lines: one-sigma values, fit, ambiguity, undetermined parameters.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let show = |k: usize| {
            let name = crate::pf_icp::surface::LOCAL_NAMES[k];
            match self.sigma[k] {
                Some(v) if k >= 4 => format!("{name} {:.3} deg", v.to_degrees()),
                Some(v) => format!("{name} {v:.3e}"),
                None => format!("{name} undetermined"),
            }
        };
        s += "one sigma    (translation of the scan centroid's image, rotation vector) ";
        s += &(0..7).map(show).collect::<Vec<_>>().join(", ");
        s += "\n";
        s += &format!(
            "fit          fitness {:.3} (within {:.4}), inlier_rmse {:.4e}\n",
            self.fitness, self.inlier_distance, self.inlier_rmse
        );
        if !self.alternatives.is_empty() {
            let as_well = self.alternatives.iter().filter(|a| a.fits_as_well).count();
            let more = match self.alternatives.len() - as_well {
                0 => String::new(),
                n => format!(", {n} more fit worse but are not ruled out"),
            };
            s += &format!(
                "warning: the shape looks symmetric: {} poses fit as well as this one within the noise{more} (see alternatives in --json)\n",
                as_well + 1
            );
        }
        if !self.undetermined.is_empty() {
            s += &format!(
                "warning: the scan cannot determine {} (collinear or planar geometry); those values are arbitrary\n",
                self.undetermined.join(", ")
            );
        }
        s
    }
}

impl RegisterReport {
    /// Build from a registration.
    pub fn new(method: &str, r: &Registration, seconds: f64) -> Self {
        let PoseRecord { scale, rotation, translation, euler_deg } = r.pose.record();
        let m = r.pose.matrix4();
        RegisterReport {
            method: method.to_string(),
            engine: "software".to_string(),
            port: None,
            scale,
            rotation,
            translation,
            euler_deg,
            matrix: std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)])),
            msd: r.msd,
            iterations: r.iterations,
            seconds,
            assessment: None,
            provenance: None,
        }
    }

    /// The report of a request's result (the board's `port` when one ran).
    pub fn of(request: &crate::request::Request, registered: &crate::request::Registered, port: Option<&str>) -> Self {
        let outcome = &registered.outcome;
        let mut report =
            RegisterReport::new(request.method.name(), &outcome.registration, outcome.elapsed.as_secs_f64());
        if let Some(pf) = &outcome.pf {
            report = report.assessed(&pf.conclusion);
            if let Some(a) = &mut report.assessment {
                a.rescued = !pf.times.rescue.is_zero();
            }
        }
        if let (Some(port), Some(run)) = (port, &registered.board) {
            report = report.on_board(port);
            if matches!(run, crate::request::BoardRun::HostDriven(_)) {
                report = report.host_driven();
            }
        }
        report
    }

    /// With what produced it.
    pub fn produced_by(mut self, provenance: Provenance) -> Self {
        self.provenance = Some(provenance);
        self
    }

    /// With PF-ICP's alternatives, uncertainty and fit.
    pub fn assessed(mut self, c: &crate::pf_icp::conclusion::Conclusion) -> Self {
        self.assessment = Some(Assessment::new(c));
        self
    }

    /// The same report for a run whose particle filter ran on the board on `port`.
    pub fn on_board(mut self, port: &str) -> Self {
        self.engine = "board".to_string();
        self.port = Some(port.to_string());
        self
    }

    /// The engine of a board run in host-driven mode (the host's filter, the board's
    /// weights): `board-host-driven`.
    pub fn host_driven(mut self) -> Self {
        self.engine = "board-host-driven".to_string();
        self
    }

    /// The human-readable form.
    pub fn text(&self) -> String {
        let mut s = String::new();
        if let Some(a) = &self.assessment {
            s += &a.verdict_line();
        }
        s += &format!("method       {}\n", self.method);
        match &self.port {
            Some(port) => s += &format!("engine       {} ({port})\n", self.engine),
            None => s += &format!("engine       {}\n", self.engine),
        }
        s += &format!("scale        {:.6}\n", self.scale);
        for (name, v) in ["phi", "theta", "psi"].iter().zip(self.euler_deg) {
            s += &format!("{:<12} {:.4} deg\n", name, v);
        }
        for (name, v) in ["tx", "ty", "tz"].iter().zip(self.translation) {
            s += &format!("{:<12} {:.6}\n", name, v);
        }
        s += "matrix (scan to model, d = s R m + T):\n";
        for row in &self.matrix {
            s += &format!("  [{:>12.6} {:>12.6} {:>12.6} {:>12.6}]\n", row[0], row[1], row[2], row[3]);
        }
        s += &format!("msd          {:.6e}\n", self.msd);
        s += &format!("iterations   {}\n", self.iterations);
        s += &format!("seconds      {:.3}\n", self.seconds);
        if let Some(a) = &self.assessment {
            s += &a.text();
        }
        if let Some(p) = &self.provenance {
            s +=
                &format!("inputs       {} model points, {} scan points\n", p.inputs.model_points, p.inputs.scan_points);
            s += &format!("reproduce    {}\n", p.command);
        }
        s
    }
}

/// One frame of `pficp track --json` (one JSON object a line).
#[derive(Clone, Debug, Serialize)]
pub struct TrackFrameReport {
    /// Frame index from 0.
    pub frame: usize,
    /// The frame's file (`-` on standard input).
    pub file: String,
    /// Where the tracked frames' filter runs: `software` or `board`.
    pub engine: String,
    /// The board's serial port when `engine` is `board`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub port: Option<String>,
    /// The track's state after the frame: `acquiring`, `tracking`, `lost`, `reacquired`.
    pub state: crate::tracking::TrackState,
    /// The verdict on the frame's pose, as `register` gives it.
    pub verdict: crate::pf_icp::verdict::Verdict,
    /// The verdict's reasons in words (empty for `confident`).
    pub reasons: Vec<String>,
    /// Scale factor.
    pub scale: f64,
    /// Rotation, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Translation.
    pub translation: [f64; 3],
    /// `[phi, theta, psi]` in degrees.
    pub euler_deg: [f64; 3],
    /// The 4x4 matrix `[[sR, T], [0, 1]]`, row-major.
    pub matrix: [[f64; 4]; 4],
    /// Names and order of the covariance's parameters.
    pub covariance_order: [&'static str; 7],
    /// Covariance (model units, scale, rad); `null` for undetermined parameters.
    pub covariance: [[Option<f64>; 7]; 7],
    /// One-sigma values in that order.
    pub sigma: [Option<f64>; 7],
    /// Fraction of scan points within the inlier distance of the model's surface.
    pub fitness: f64,
    /// RMS distance of those points.
    pub inlier_rmse: f64,
    /// Share of the scan on the surface within the noise.
    pub explained: f64,
    /// Other poses that fit as well.
    pub alternatives: Vec<PoseRecord>,
    /// Whether the frame ran a global registration.
    pub global: bool,
    /// Wall time of the frame [s].
    pub seconds: f64,
}

impl TrackFrameReport {
    /// From the tracker's frame read from `file`, its filter run by `engine` (`software` or
    /// `board`, on `port`).
    pub fn new(file: &str, f: &crate::tracking::TrackFrame, engine: &str, port: Option<&str>) -> Self {
        let PoseRecord { scale, rotation, translation, euler_deg } = f.pose.record();
        let m = f.pose.matrix4();
        TrackFrameReport {
            frame: f.frame,
            file: file.to_string(),
            engine: engine.to_string(),
            port: port.map(str::to_string),
            state: f.state,
            verdict: f.verdict,
            reasons: f.reasons.clone(),
            scale,
            rotation,
            translation,
            euler_deg,
            matrix: std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)])),
            covariance_order: crate::pf_icp::surface::LOCAL_NAMES,
            covariance: f.uncertainty.covariance,
            sigma: f.uncertainty.sigma,
            fitness: f.fit.fitness,
            inlier_rmse: f.fit.inlier_rmse,
            explained: f.checks.explained,
            alternatives: f.alternatives.iter().map(|p| p.record()).collect(),
            global: f.global,
            seconds: f.seconds,
        }
    }

    /// One line: frame, state, verdict, pose, widest sigmas, time.
    pub fn text(&self) -> String {
        let deg = |k: usize| self.sigma[k].map_or("undetermined".to_string(), |v| format!("{:.3}", v.to_degrees()));
        let sigma_deg = (4..7).map(deg).collect::<Vec<_>>().join("/");
        format!(
            "frame {:>5} {:<10} {:<10} scale {:.5} euler_deg [{:.3}, {:.3}, {:.3}] t [{:.5}, {:.5}, {:.5}] \
             sigma_deg {} fitness {:.3} {:.4} s {}\n",
            self.frame,
            self.state.name(),
            self.verdict.name(),
            self.scale,
            self.euler_deg[0],
            self.euler_deg[1],
            self.euler_deg[2],
            self.translation[0],
            self.translation[1],
            self.translation[2],
            sigma_deg,
            self.fitness,
            self.seconds,
            self.file
        )
    }
}

/// A table of the 7 parameters for several poses (columns), angles in degrees.
pub fn pose_table(columns: &[(&str, &Pose)]) -> String {
    let mut s = format!("{:<12}", "parameter");
    for (name, _) in columns {
        s += &format!("{:>14}", name);
    }
    s += "\n";
    type Row = (&'static str, fn(&Pose) -> f64);
    let rows: [Row; 7] = [
        ("phi (deg)", |p| p.euler_deg()[0]),
        ("theta (deg)", |p| p.euler_deg()[1]),
        ("psi (deg)", |p| p.euler_deg()[2]),
        ("tx", |p| p.translation.x),
        ("ty", |p| p.translation.y),
        ("tz", |p| p.translation.z),
        ("scale", |p| p.scale),
    ];
    for (label, f) in rows {
        s += &format!("{:<12}", label);
        for (_, p) in columns {
            s += &format!("{:>14.4}", f(p));
        }
        s += "\n";
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_has_the_documented_keys() {
        let pose = Pose::from_params(&[1.0, 2.0, 3.0, 0.5, 0.1, 0.2, 0.3]);
        let r = Registration { pose, msd: 0.25, iterations: 7, errors: vec![] };
        let v = serde_json::to_value(RegisterReport::new("icp", &r, 1.5)).unwrap();
        for key in ["scale", "rotation", "translation", "euler_deg", "msd", "iterations", "seconds", "engine"] {
            assert!(v.get(key).is_some(), "missing {key}");
        }
        assert_eq!(v["engine"], "software");
        assert!(v.get("port").is_none());
        let b = serde_json::to_value(RegisterReport::new("pf-icp", &r, 1.5).on_board("/dev/ttyUSB0")).unwrap();
        assert_eq!((b["engine"].as_str(), b["port"].as_str()), (Some("board"), Some("/dev/ttyUSB0")));
        let h = RegisterReport::new("pf-icp", &r, 1.5).on_board("/dev/ttyUSB0").host_driven();
        assert_eq!(h.engine, "board-host-driven");
        assert!(h.text().contains("engine       board-host-driven (/dev/ttyUSB0)"));
        assert_eq!(v["translation"][2], 3.0);
        assert_eq!(v["matrix"][0][3], 1.0);
        assert!((v["euler_deg"][2].as_f64().unwrap() - 0.3f64.to_degrees()).abs() < 1e-9);
        let t = RegisterReport::new("icp", &r, 1.5).text();
        assert!(t.contains("iterations   7"));
        let tab = pose_table(&[("truth", &pose)]);
        assert!(tab.contains("scale") && tab.contains("0.5000"));
    }

    #[test]
    fn the_command_quotes_what_a_shell_would_split() {
        let inputs = Inputs { model: "my model.ply".into(), scan: "it's.xyz".into(), model_points: 10, scan_points: 9 };
        let settings = Settings {
            seed: 3,
            clusters: 4,
            particles: 5,
            iterations: 6,
            init: "nearest".into(),
            scale: None,
            scale_range: None,
            viewpoint: None,
            rescue: true,
            board_points: Some(200),
        };
        let p = Provenance::new("pf-icp", inputs, settings, Some("/dev/ttyUSB0"), false);
        assert_eq!(
            p.command,
            "pficp register --model 'my model.ply' --scan 'it'\\''s.xyz' --method pf-icp --clusters 4 --particles 5 \
             --iterations 6 --seed 3 --init nearest --board /dev/ttyUSB0 --board-points 200"
        );
        let v = serde_json::to_value(
            RegisterReport::new(
                "pf-icp",
                &Registration { pose: Pose::identity(), msd: 0.0, iterations: 1, errors: vec![] },
                0.1,
            )
            .produced_by(p),
        )
        .unwrap();
        assert_eq!(v["settings"]["board_points"], 200);
        assert_eq!(v["inputs"]["scan_points"], 9);
    }
}
