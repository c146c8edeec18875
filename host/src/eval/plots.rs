//! The figures, as SVG (`pficp eval` writes them into its `out_dir`):
//!
//! - `fig15_error_per_iteration.svg`: how the error falls, iteration by iteration, on a
//!   case where PF-ICP has to work: model-2 under its Table 1 transform, scanned
//!   independently of the model's points ([`Sampling::Independent`], `scan_points` points,
//!   seed `mix(seed, 15)`; in the paper setting the scan is the model's own points moved
//!   and PF-ICP's start is already exact, so its line was a single point). Every curve is
//!   the MSD of the whole scan (mean squared distance to the closest model point, what
//!   ICP minimises), on a log axis labelled in decades: ICP with Welsch and with Cauchy
//!   weights before each iteration, from the identity; PF-ICP (the success table's
//!   settings, seeded by `seed`) at its filter's estimate after each filter iteration,
//!   the last point after the polish; a flat line at the MSD of the true pose, which is
//!   not zero since the scan's points are not the model's.
//! - `fig9_distance_vs_drift_model1.svg`, `fig12_distance_vs_drift_model2.svg`: the mean
//!   closest-point distance between the model and the scan (paper setting) mapped by the
//!   truth with some parameters drifted by `k sigma`, `k` in `-3..3`. `sigma` is the
//!   `K = 100` Algorithm 5 standard deviation of Tables 2 and 3, floored at
//!   [`MIN_SIGMA_DEG`], [`MIN_SIGMA_DIAG`] of the diagonal and [`MIN_SIGMA_SCALE`] of the
//!   scale. In the paper setting Algorithm 5's spread is zero (index pairing is exact), so
//!   the floors decide; they are wide enough (+-15 deg, +-15% of the diagonal) to show the
//!   shoulders of the distance function about 10 deg from the truth, which 2 deg floors
//!   (plain V shapes) hide.
//!
//! Axes ([`Axis`]): ticks at round steps with as many decimals as the step needs, or on a
//! log axis at whole decades only, labelled `10⁻⁴` (superscript digits), with light lines
//! at 2 to 9 times each decade. Titles go on their own lines above the plot, the
//! settings on a smaller line below the title, so no text leaves the canvas (the tests
//! render every figure to PNG and check that).

use super::covariance_tables::algorithm5;
use super::{mix, EvalOptions};
use crate::cloud::bbox_diagonal;
use crate::datasets::{make, ModelId, Sampling, ScanSpec};
use crate::geometry::{param, Params, Pose};
use crate::nn::NearestNeighbours;
use crate::pf_icp::PfIcpSettings;
use crate::registration::icp::msd;
use crate::registration::methods::{run as run_method, Method, MethodSettings};
use anyhow::anyhow;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;

/// Smallest drift sigma of an angle (deg).
pub const MIN_SIGMA_DEG: f64 = 5.0;
/// Smallest drift sigma of a translation, as a fraction of the diagonal.
pub const MIN_SIGMA_DIAG: f64 = 0.05;
/// Smallest drift sigma of the scale, relative.
pub const MIN_SIGMA_SCALE: f64 = 0.05;
/// MSD values below this are drawn at this value on the log axis.
pub const LOG_FLOOR: f64 = 1e-12;
/// Drift steps per sigma.
const STEPS_PER_SIGMA: usize = 20;
/// Canvas size (px).
const CANVAS: (u32, u32) = (960, 640);
/// Most ticks on a linear axis.
const MAX_TICKS: f64 = 10.0;
/// Series with at most this many points get a marker at each point.
const MAX_MARKED_POINTS: usize = 80;

/// Colours of the series, in order (dark enough to read on white).
const COLOURS: [RGBColor; 6] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// The colour of series `i`.
fn series_colour(i: usize) -> RGBColor {
    COLOURS[i % COLOURS.len()]
}

/// A named curve.
type Series = (String, Vec<(f64, f64)>);

/// Write all figures into `opts.out_dir`; returns their paths.
pub fn run(opts: &EvalOptions) -> anyhow::Result<Vec<String>> {
    let start = std::time::Instant::now();
    let bar = crate::progress::Progress::bar("[eval] figures", 3, "figures");
    let mut out = Vec::new();
    bar.message("Fig. 15");
    out.push(fig15(opts)?);
    bar.inc();
    bar.message("Fig. 9");
    out.push(drift_figure(
        ModelId::Model1,
        9,
        &[&[param::PHI, param::C], &[param::PSI, param::PHI, param::A], &[param::PSI]],
        opts,
    )?);
    bar.inc();
    bar.message("Fig. 12");
    out.push(drift_figure(ModelId::Model2, 12, &[&[param::THETA], &[param::THETA, param::PSI, param::S]], opts)?);
    bar.finish(format_args!("[eval] Figs. 15, 9 and 12 ({:.1} s)", start.elapsed().as_secs_f64()));
    Ok(out)
}

/// The curves of Fig. 15 (PF-ICP's first) and the MSD at the true pose.
fn fig15_series(opts: &EvalOptions) -> (Vec<Series>, f64, usize) {
    let id = ModelId::Model2;
    let truth = id.table1_truth();
    let spec =
        ScanSpec { sampling: Sampling::Independent { points: opts.scan_points }, noise: 0.0, seed: mix(opts.seed, 15) };
    let ds = make(id, opts.model_points, &truth, &spec);
    let nn = NearestNeighbours::new(&ds.model);
    // The success table's settings.
    let settings = MethodSettings { pf: PfIcpSettings { seed: opts.seed, ..Default::default() } };
    let pf = run_method(Method::PfIcp, &nn, &ds.scan, &settings);
    let mut pf_pts: Vec<(f64, f64)> = Vec::new();
    if let Some(r) = pf.pf.as_ref() {
        // 0: the filter's start (the global search's best hypothesis, or the k-means start).
        let start = r.hypotheses.first().map_or(r.initial.pose, |h| h.pose);
        pf_pts.push((0.0, msd(&nn, &ds.scan, &start)));
        pf_pts.extend(r.filter_poses.iter().enumerate().map(|(i, p)| ((i + 1) as f64, msd(&nn, &ds.scan, p))));
    }
    pf_pts.push((pf_pts.len() as f64, pf.registration.msd));
    let mut series = vec![("PF-ICP (0: its start; filter iterations; last: the polish)".to_string(), pf_pts)];
    for (m, name) in [(Method::Welsch, "ICP Welsch"), (Method::Cauchy, "ICP Cauchy")] {
        let r = run_method(m, &nn, &ds.scan, &settings).registration;
        series.push((name.to_string(), r.errors.iter().enumerate().map(|(i, &e)| (i as f64, e)).collect()));
    }
    let at_truth = msd(&nn, &ds.scan, &truth);
    (series, at_truth, ds.model.len())
}

fn fig15(opts: &EvalOptions) -> anyhow::Result<String> {
    let (series, at_truth, model_len) = fig15_series(opts);
    let (x1, (y0, y1)) = extent(&series);
    let path = opts.out_dir.join("fig15_error_per_iteration.svg");
    let chart = Chart {
        title: "Fig. 15: model-2, independent scan: error per iteration",
        subtitle: &format!(
            "Table 1 transform; model {model_len} points, scan {} points sampled independently; \
             PF-ICP with its default settings; seed {}",
            opts.scan_points, opts.seed
        ),
        x: Axis::linear(
            0.0,
            x1.max(1.0),
            "iteration (0: start; ICP: before iteration i; PF-ICP: after filter iteration i)",
        ),
        y: Axis::log10(
            y0.min(at_truth),
            y1.max(at_truth),
            "MSD of the whole scan (mean squared closest-point distance)",
        ),
        reference: Some(("MSD at the true pose", at_truth)),
        legend: SeriesLabelPosition::UpperRight,
    };
    line_chart(&path, &chart, &series)?;
    Ok(path.display().to_string())
}

/// The tracking benchmark's figure: each sequence's rotation error [deg] per frame (log
/// axis), the tolerance as the reference line. Returns the path written.
pub fn tracking_figure(
    path: &Path,
    subtitle: &str,
    series: &[(String, Vec<(f64, f64)>)],
    tolerance_deg: f64,
) -> anyhow::Result<()> {
    let frames = series.iter().flat_map(|(_, p)| p.iter().map(|q| q.0)).fold(1.0f64, f64::max);
    let worst = series.iter().flat_map(|(_, p)| p.iter().map(|q| q.1)).fold(tolerance_deg, f64::max);
    let chart = Chart {
        title: "Tracking: rotation error over the frames",
        subtitle,
        x: Axis::linear(0.0, frames, "frame"),
        y: Axis::log10(1e-3, worst.min(180.0), "rotation error (deg)"),
        reference: Some(("tolerance", tolerance_deg)),
        legend: SeriesLabelPosition::UpperLeft,
    };
    line_chart(path, &chart, series)
}

/// Mean closest-point distance of `scan` mapped by `pose` to the model.
fn mean_distance(nn: &NearestNeighbours, scan: &[nalgebra::Point3<f64>], pose: &Pose) -> f64 {
    let moved = pose.apply_all(scan);
    nn.closest_all(&moved).iter().map(|c| c.dist2.sqrt()).sum::<f64>() / scan.len() as f64
}

fn drift_figure(id: ModelId, fig: u32, sets: &[&[usize]], opts: &EvalOptions) -> anyhow::Result<String> {
    let truth = id.table1_truth();
    let ds = make(id, opts.model_points, &truth, &ScanSpec { sampling: Sampling::Paper, noise: 0.0, seed: opts.seed });
    let nn = NearestNeighbours::new(&ds.model);
    let diag = bbox_diagonal(&ds.model);
    // Algorithm 5 with K = 100, in parameter order (radians).
    let a5 = algorithm5(&nn, &ds.scan, 100, opts.seed).std_dev;
    let measured: Params = [a5[3], a5[4], a5[5], a5[6], a5[0].to_radians(), a5[1].to_radians(), a5[2].to_radians()];
    let floor: Params = [
        MIN_SIGMA_DIAG * diag,
        MIN_SIGMA_DIAG * diag,
        MIN_SIGMA_DIAG * diag,
        MIN_SIGMA_SCALE * truth.scale,
        MIN_SIGMA_DEG.to_radians(),
        MIN_SIGMA_DEG.to_radians(),
        MIN_SIGMA_DEG.to_radians(),
    ];
    let sigma: Params = std::array::from_fn(|i| measured[i].max(floor[i]));
    let p0 = truth.to_params();
    let names = ["tx", "ty", "tz", "s", "phi", "theta", "psi"];
    let n = 3 * STEPS_PER_SIGMA;
    let series: Vec<Series> = sets
        .iter()
        .map(|set| {
            let pts = (-(n as i64)..=n as i64)
                .map(|j| {
                    let k = j as f64 / STEPS_PER_SIGMA as f64;
                    let mut p = p0;
                    for &i in *set {
                        p[i] += k * sigma[i];
                    }
                    (k, mean_distance(&nn, &ds.scan, &Pose::from_params(&p)))
                })
                .collect();
            let name = set.iter().map(|&i| names[i]).collect::<Vec<_>>().join(", ");
            (format!("drift {{{name}}}"), pts)
        })
        .collect();
    let sig = |i: usize| {
        if i >= param::PHI {
            format!("{}={:.2} deg", names[i], sigma[i].to_degrees())
        } else {
            format!("{}={:.3}", names[i], sigma[i])
        }
    };
    let mut used: Vec<usize> = sets.iter().flat_map(|s| s.iter().copied()).collect();
    used.sort_unstable();
    used.dedup();
    let sigmas = used.into_iter().map(sig).collect::<Vec<_>>().join(", ");
    let slug = id.name().replace('-', "");
    let path = opts.out_dir.join(format!("fig{fig}_distance_vs_drift_{slug}.svg"));
    let (_, (_, y1)) = extent(&series);
    let chart = Chart {
        title: &format!("Fig. {fig}: {}, mean distance to the model vs parameter drift", id.name()),
        subtitle: &format!("paper-setting scan of {} points; sigma: {sigmas}", ds.scan.len()),
        x: Axis::linear(-3.0, 3.0, "drift of the parameters (multiples of sigma)"),
        y: Axis::linear(0.0, (y1 * 1.05).max(1e-9), "mean closest-point distance"),
        reference: None,
        // The V shapes leave the top middle free.
        legend: SeriesLabelPosition::UpperMiddle,
    };
    line_chart(&path, &chart, &series)?;
    Ok(path.display().to_string())
}

/// Largest x and the y range of all curves.
fn extent(series: &[Series]) -> (f64, (f64, f64)) {
    let mut x1 = f64::NEG_INFINITY;
    let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
    for (_, pts) in series {
        for &(x, y) in pts {
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    (x1, (y0, y1))
}

/// `10` with `exponent` in superscript digits (`10⁻⁴`).
pub fn decade_label(exponent: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::from("10");
    if exponent < 0 {
        s.push('⁻');
    }
    s.extend(exponent.unsigned_abs().to_string().bytes().map(|b| DIGITS[usize::from(b - b'0')]));
    s
}

/// One axis of a chart: what is drawn (values, or their log10 on a log axis), where the
/// ticks go and how they read.
struct Axis {
    /// Drawn range (log10 of the values on a log axis).
    range: Range<f64>,
    /// Labelled ticks (drawn values).
    ticks: Vec<f64>,
    /// Light grid lines without labels (drawn values).
    minor: Vec<f64>,
    /// Whether values are drawn as their log10.
    log: bool,
    /// Decimals of a linear tick label.
    decimals: usize,
    /// Axis description.
    desc: String,
}

impl Axis {
    /// A linear axis over `lo..hi` with ticks at a round step (1, 2 or 5 times a power of
    /// ten, at most [`MAX_TICKS`] of them).
    fn linear(lo: f64, hi: f64, desc: &str) -> Self {
        let (lo, hi) = if hi > lo { (lo, hi) } else { (lo, lo + 1.0) };
        let raw = (hi - lo) / MAX_TICKS;
        let mag = 10f64.powf(raw.log10().floor());
        let step =
            [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw * (1.0 - 1e-9)).unwrap_or(10.0 * mag);
        let first = (lo / step - 1e-9).ceil() as i64;
        let last = (hi / step + 1e-9).floor() as i64;
        let ticks = (first..=last).map(|k| k as f64 * step).collect();
        let decimals = (-step.log10().floor()).max(0.0) as usize;
        Self { range: lo..hi, ticks, minor: Vec::new(), log: false, decimals, desc: desc.to_string() }
    }

    /// A log axis over whole decades covering `lo..hi` (values below [`LOG_FLOOR`] are
    /// drawn there), a tick at every decade (every second or more when there are many).
    fn log10(lo: f64, hi: f64, desc: &str) -> Self {
        let lo = lo.max(LOG_FLOOR).log10().floor() as i32;
        let hi = (hi.max(LOG_FLOOR).log10().ceil() as i32).max(lo + 1);
        let every = (hi - lo + 9) / 10;
        let ticks = (lo..=hi).filter(|e| (e - lo) % every == 0).map(f64::from).collect();
        let minor = (lo..hi)
            .flat_map(|e| (2..10).map(move |m| f64::from(e) + f64::from(m).log10()))
            .filter(|_| every == 1)
            .collect();
        Self { range: f64::from(lo)..f64::from(hi), ticks, minor, log: true, decimals: 0, desc: desc.to_string() }
    }

    /// The coordinate plotters draws on.
    fn coord(&self) -> Ticked {
        Ticked { range: self.range.clone(), ticks: self.ticks.clone(), minor: self.minor.clone() }
    }

    /// Where a value is drawn.
    fn map(&self, v: f64) -> f64 {
        if self.log {
            v.max(LOG_FLOOR).log10()
        } else {
            v
        }
    }

    /// A tick's label.
    fn label(&self, v: f64) -> String {
        if self.log {
            decade_label(v.round() as i32)
        } else {
            let s = format!("{v:.*}", self.decimals);
            // No "-0" or "-0.00".
            if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
                s[1..].to_string()
            } else {
                s
            }
        }
    }
}

/// A linear coordinate with the axis' own ticks (bold, labelled) and light lines.
struct Ticked {
    range: Range<f64>,
    ticks: Vec<f64>,
    minor: Vec<f64>,
}

impl Ranged for Ticked {
    type ValueType = f64;
    type FormatOption = DefaultFormatting;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let span = self.range.end - self.range.start;
        let t = if span > 0.0 { (v - self.range.start) / span } else { 0.0 };
        let px = f64::from(limit.0) + t * (f64::from(limit.1) - f64::from(limit.0));
        // Far outside points are clamped (a float to int cast saturates anyway).
        px.round().clamp(-1e6, 1e6) as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.range.clone()
    }
}

/// What a line chart shows besides its series.
struct Chart<'a> {
    /// The title, on its own line.
    title: &'a str,
    /// The settings, on a smaller line under the title.
    subtitle: &'a str,
    /// The horizontal axis.
    x: Axis,
    /// The vertical axis.
    y: Axis,
    /// A thin grey horizontal line at this value, drawn under the series, and its name.
    reference: Option<(&'a str, f64)>,
    /// Where the legend goes.
    legend: SeriesLabelPosition,
}

/// One line chart with a legend. Series `i` has colour [`series_colour`]`(i)` (the tests
/// find PF-ICP's line by it).
fn line_chart(path: &Path, chart_spec: &Chart, series: &[Series]) -> anyhow::Result<()> {
    let Chart { title, subtitle, x, y, reference, legend } = chart_spec;
    let (reference, legend) = (*reference, legend.clone());
    let err = |e: &dyn std::fmt::Display| anyhow!("drawing {}: {e}", path.display());
    let root = SVGBackend::new(path, CANVAS).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let root = root.margin(10, 10, 10, 10);
    let area = root.titled(title, ("sans-serif", 22)).map_err(|e| err(&e))?;
    let area =
        area.titled(subtitle, ("sans-serif", 14).into_font().color(&RGBColor(80, 80, 80))).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&area)
        .margin_top(10)
        .margin_right(30)
        .x_label_area_size(60)
        .y_label_area_size(if y.log { 70 } else { 90 })
        .build_cartesian_2d(x.coord(), y.coord())
        .map_err(|e| err(&e))?;
    let x_label = |v: &f64| x.label(*v);
    let y_label = |v: &f64| y.label(*v);
    chart
        .configure_mesh()
        .x_desc(x.desc.as_str())
        .y_desc(y.desc.as_str())
        .x_label_formatter(&x_label)
        .y_label_formatter(&y_label)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 15))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| err(&e))?;
    if let Some((name, level)) = reference {
        let grey = RGBColor(90, 90, 90);
        let (x0, x1) = (x.range.start, x.range.end);
        chart
            .draw_series(LineSeries::new([(x0, y.map(level)), (x1, y.map(level))], grey.stroke_width(1)))
            .map_err(|e| err(&e))?
            .label(name)
            .legend(move |(lx, ly)| PathElement::new(vec![(lx, ly), (lx + 20, ly)], grey.stroke_width(1)));
    }
    for (i, (name, pts)) in series.iter().enumerate() {
        let color = series_colour(i);
        let drawn: Vec<(f64, f64)> = pts.iter().map(|&(px, py)| (x.map(px), y.map(py))).collect();
        chart
            .draw_series(LineSeries::new(drawn.iter().copied(), color.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(name.as_str())
            .legend(move |(lx, ly)| PathElement::new(vec![(lx, ly), (lx + 20, ly)], color.stroke_width(2)));
        if drawn.len() > 2 && drawn.len() <= MAX_MARKED_POINTS {
            chart.draw_series(drawn.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(|e| err(&e))?;
        }
    }
    chart
        .configure_series_labels()
        .position(legend)
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The system's fonts, with `sans-serif` (what plotters asks for) mapped to a common
/// family that is there (`None`: none of DejaVu, Liberation, Noto or Free Sans).
#[cfg(feature = "png")]
pub fn fonts() -> Option<std::sync::Arc<resvg::usvg::fontdb::Database>> {
    let mut db = resvg::usvg::fontdb::Database::new();
    db.load_system_fonts();
    let families: Vec<String> = db.faces().flat_map(|f| f.families.iter().map(|(n, _)| n.clone())).collect();
    let sans = ["DejaVu Sans", "Liberation Sans", "Noto Sans", "FreeSans"]
        .iter()
        .map(|s| s.to_string())
        .find(|s| families.contains(s))?;
    db.set_sans_serif_family(sans);
    Some(std::sync::Arc::new(db))
}

/// Render the SVG file `svg` to the PNG file `png` (without a common sans-serif font the
/// figure's text is left out, and a note says so).
#[cfg(feature = "png")]
pub fn render_png(svg: &Path, png: &Path) -> anyhow::Result<()> {
    use anyhow::Context;
    use resvg::tiny_skia::{Pixmap, Transform};
    use resvg::usvg::{Options, Tree};
    let text = std::fs::read_to_string(svg).with_context(|| format!("cannot read {}", svg.display()))?;
    let mut opt = Options::default();
    match fonts() {
        Some(db) => opt.fontdb = db,
        None => crate::progress::note(format_args!(
            "{}: no DejaVu, Liberation, Noto or Free Sans font: the PNG has no text",
            png.display()
        )),
    }
    let tree = Tree::from_str(&text, &opt).with_context(|| format!("{}", svg.display()))?;
    let size = tree.size().to_int_size();
    let mut pixmap = Pixmap::new(size.width(), size.height()).context("an empty figure")?;
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(&tree, Transform::default(), &mut pixmap.as_mut());
    pixmap.save_png(png).with_context(|| format!("cannot write {}", png.display()))
}

#[cfg(all(test, feature = "png"))]
mod tests {
    //! Every figure [`run`] writes is rendered to PNG (resvg, with the system's fonts: the
    //! test fails when there are none; `tests/run-all` installs Debian's
    //! `fonts-dejavu-core` when missing) and checked: not blank, every text inside the
    //! canvas, and for Fig. 15 decade labels on the log axis and more than two PF-ICP
    //! points.

    use super::*;
    use resvg::tiny_skia::{Pixmap, Transform};
    use resvg::usvg::{fontdb, roxmltree, Node, Options, TextAnchor, Tree};
    use std::collections::HashSet;
    use std::sync::Arc;

    /// The system's fonts ([`super::fonts`]; the tests need one).
    fn fonts() -> Arc<fontdb::Database> {
        super::fonts().unwrap_or_else(|| {
            panic!("no DejaVu, Liberation, Noto or Free Sans font: install fonts-dejavu-core (tests/run-all does)")
        })
    }

    /// A text element as laid out: its string, its anchor and its box on the canvas.
    struct Label {
        text: String,
        anchor: TextAnchor,
        rect: resvg::tiny_skia::Rect,
    }

    fn labels(group: &resvg::usvg::Group, out: &mut Vec<Label>) {
        for node in group.children() {
            match node {
                Node::Group(g) => labels(g, out),
                Node::Text(t) => out.push(Label {
                    text: t.chunks().iter().map(|c| c.text()).collect(),
                    anchor: t.chunks().first().map_or(TextAnchor::Start, |c| c.anchor()),
                    rect: t.abs_stroke_bounding_box(),
                }),
                _ => {}
            }
        }
    }

    /// Render `svg` to PNG (written to `png`), check it is not blank and that every text
    /// is laid out and inside the canvas; returns the texts.
    fn check_figure(svg: &str, png: &Path, db: &Arc<fontdb::Database>) -> Vec<Label> {
        let name = png.display();
        let opt = Options { fontdb: db.clone(), ..Default::default() };
        let tree = Tree::from_str(svg, &opt).unwrap_or_else(|e| panic!("{name}: {e}"));
        let size = tree.size().to_int_size();
        let mut pixmap = Pixmap::new(size.width(), size.height()).expect("canvas");
        resvg::render(&tree, Transform::default(), &mut pixmap.as_mut());
        pixmap.save_png(png).unwrap_or_else(|e| panic!("{name}: {e}"));

        // Not blank: many pixels off the background, in more than one colour.
        let px = pixmap.pixels();
        let background = px[0];
        let off: Vec<_> = px.iter().filter(|p| **p != background).collect();
        let colours: HashSet<[u8; 4]> = off.iter().map(|p| [p.red(), p.green(), p.blue(), p.alpha()]).collect();
        assert!(off.len() * 100 > px.len(), "{name}: only {} of {} pixels drawn", off.len(), px.len());
        assert!(colours.len() > 2, "{name}: {} colours", colours.len());

        // Every <text> laid out (a text without a font is dropped) and inside the canvas.
        let doc = roxmltree::Document::parse(svg).unwrap_or_else(|e| panic!("{name}: {e}"));
        let texts = doc.descendants().filter(|n| n.has_tag_name("text")).count();
        let mut out = Vec::new();
        labels(tree.root(), &mut out);
        assert_eq!(out.len(), texts, "{name}: texts laid out");
        let (w, h) = (size.width() as f32, size.height() as f32);
        for l in &out {
            let r = l.rect;
            assert!(
                r.width() > 0.0 && r.left() >= 0.0 && r.top() >= 0.0 && r.right() <= w && r.bottom() <= h,
                "{name}: text {:?} at {r:?} is not inside the {w} x {h} canvas",
                l.text
            );
        }
        out
    }

    /// `10` with a superscript exponent (`10⁻⁴`, `10⁰`, `10³`).
    fn is_decade_label(s: &str) -> bool {
        let Some(exp) = s.trim().strip_prefix("10") else { return false };
        let digits = exp.strip_prefix('⁻').unwrap_or(exp);
        !digits.is_empty() && digits.chars().all(|c| "⁰¹²³⁴⁵⁶⁷⁸⁹".contains(c))
    }

    #[test]
    fn every_figure_renders_readably() {
        let dir = tempfile::tempdir().unwrap();
        let opts = EvalOptions {
            out_dir: dir.path().to_path_buf(),
            model_points: 600,
            scan_points: 600,
            seed: 1,
            ..Default::default()
        };
        let paths = run(&opts).unwrap();
        assert_eq!(paths.len(), 3);
        let db = fonts();
        for path in &paths {
            let svg = std::fs::read_to_string(path).unwrap();
            let png = Path::new(path).with_extension("png");
            let texts = check_figure(&svg, &png, &db);
            // To look at them: PFICP_KEEP_FIGURES=/some/dir cargo test ... every_figure
            if let Some(keep) = std::env::var_os("PFICP_KEEP_FIGURES") {
                let keep = Path::new(&keep);
                std::fs::create_dir_all(keep).unwrap();
                for f in [Path::new(path), png.as_path()] {
                    std::fs::copy(f, keep.join(f.file_name().unwrap())).unwrap();
                }
            }
            assert!(texts.len() > 5, "{path}: {} texts", texts.len());
            if !path.ends_with("fig15_error_per_iteration.svg") {
                continue;
            }
            // The log axis: its tick labels (right-aligned, left of the plot) are decades.
            let ticks: Vec<&str> =
                texts.iter().filter(|l| matches!(l.anchor, TextAnchor::End)).map(|l| l.text.trim()).collect();
            assert!(ticks.len() >= 2, "{path}: y tick labels {ticks:?}");
            assert!(ticks.iter().all(|t| is_decade_label(t)), "{path}: y tick labels {ticks:?}");
            // PF-ICP is in the legend (whose texts start left) and is the first series,
            // drawn in the first series' colour: its line has more than two points.
            let legend: Vec<&str> =
                texts.iter().filter(|l| matches!(l.anchor, TextAnchor::Start)).map(|l| l.text.trim()).collect();
            assert!(legend.iter().any(|t| t.starts_with("PF-ICP")), "{path}: legend {legend:?}");
            let c = series_colour(0);
            let colour = format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
            let doc = roxmltree::Document::parse(&svg).unwrap();
            let points = doc
                .descendants()
                .filter(|n| {
                    n.has_tag_name("polyline") && n.attribute("stroke").is_some_and(|s| s.eq_ignore_ascii_case(&colour))
                })
                .map(|n| n.attribute("points").unwrap_or("").split_whitespace().count())
                .max()
                .unwrap_or(0);
            assert!(points > 2, "{path}: PF-ICP's line ({colour}) has {points} points");
        }
    }

    #[test]
    fn decade_labels_are_recognised() {
        assert!(is_decade_label("10⁻⁴") && is_decade_label("10⁰") && is_decade_label("10¹²"));
        assert!(!is_decade_label("9.99999999e-5") && !is_decade_label("10") && !is_decade_label("1e-4"));
    }
}
