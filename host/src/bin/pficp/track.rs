//! `pficp track`: a sequence of scans against one model, frame after frame.

use crate::args::TrackArgs;
use crate::load;
use anyhow::{bail, Context, Result};
use pficp::cli::TrackFrameReport;
use pficp::cloud::Cloud;
use pficp::io::{format_from_path, read_points_from_bytes, Format};
use pficp::nn::NearestNeighbours;
use pficp::progress::note;
use pficp::tracking::{TrackSettings, Tracker, MIN_FRAME_POINTS};
use std::io::{BufRead, Write};
use std::path::PathBuf;

pub(crate) fn track(a: &TrackArgs) -> Result<()> {
    pficp::tracking::check_fps(a.fps)?;
    let registration = a.pf.settings()?;
    let model = load(&a.model, "model")?;
    let nn = NearestNeighbours::new(model.points());
    let settings = TrackSettings { registration, fps: a.fps, ..Default::default() };
    // Open the port before the work starts: a missing or silent board fails at once.
    let mut client = a.board.as_deref().map(|port| a.link.open(port)).transpose()?;
    let mut tracker = match client.as_mut() {
        Some(c) => {
            let (t, uploaded) = Tracker::on_board(&nn, settings, c)?;
            note(format_args!(
                "{}",
                if uploaded { "uploaded the model to the board" } else { "the board holds the model already" }
            ));
            t
        }
        None => Tracker::new(&nn, settings)?,
    };
    let (engine, port) = match &a.board {
        Some(p) => ("board", Some(p.as_str())),
        None => ("software", None),
    };
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut emit = |file: &str, scan: &Cloud, tracker: &mut Tracker| -> Result<()> {
        let frame = tracker.update(scan.points())?;
        let report = TrackFrameReport::new(file, &frame, engine, port);
        if a.json {
            writeln!(out, "{}", serde_json::to_string(&report)?)?;
        } else {
            write!(out, "{}", report.text())?;
        }
        out.flush()?;
        Ok(())
    };
    if a.scans.as_os_str() == "-" {
        let stdin = std::io::stdin();
        let mut lines = stdin.lock();
        let mut block = Vec::new();
        let mut line = String::new();
        let mut index = 0usize;
        let mut lines_in_block = 0usize;
        loop {
            line.clear();
            let n = lines.read_line(&mut line).context("cannot read standard input")?;
            let end = n == 0;
            if end || line.trim().is_empty() {
                if !block.is_empty() {
                    let scan = frame_cloud(&block, index)?;
                    emit("-", &scan, &mut tracker)?;
                    index += 1;
                    block.clear();
                    lines_in_block = 0;
                }
                if end {
                    break;
                }
            } else {
                lines_in_block += 1;
                if lines_in_block > pficp::cloud::MAX_CLOUD_POINTS {
                    bail!(
                        "standard input, frame {index}: more than {} lines without an empty line (a frame holds at most \
                         that many points)",
                        pficp::cloud::MAX_CLOUD_POINTS
                    );
                }
                block.extend_from_slice(line.as_bytes());
            }
        }
        if index == 0 {
            bail!("standard input held no frame (frames are blocks of `x y z` lines ended by an empty line)");
        }
        return Ok(());
    }
    let files = frame_files(&a.scans)?;
    note(format_args!("tracking {} frames against {} model points", files.len(), model.len()));
    for path in files {
        let scan = load(&path, "scan")?;
        if scan.len() < MIN_FRAME_POINTS {
            bail!("{}: a frame needs at least {MIN_FRAME_POINTS} points (got {})", path.display(), scan.len());
        }
        emit(&path.display().to_string(), &scan, &mut tracker)?;
    }
    Ok(())
}

/// Frame `index` of standard input from its lines.
fn frame_cloud(block: &[u8], index: usize) -> Result<Cloud> {
    let points = read_points_from_bytes(block, Format::Xyz)
        .map_err(|e| anyhow::anyhow!("standard input, frame {index}: {e}"))?;
    if points.len() < MIN_FRAME_POINTS {
        bail!("standard input, frame {index}: a frame needs at least {MIN_FRAME_POINTS} points (got {})", points.len());
    }
    if points.len() > pficp::cloud::MAX_CLOUD_POINTS {
        bail!("standard input, frame {index}: more than {} points", pficp::cloud::MAX_CLOUD_POINTS);
    }
    Cloud::new("scan", points).map_err(|e| anyhow::anyhow!("standard input, frame {index}: {e}"))
}

/// The cloud files of `dir` in name order.
fn frame_files(dir: &std::path::Path) -> Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        bail!("--scans {}: not a folder (give a folder of frames, or - for standard input)", dir.display());
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && format_from_path(p).is_ok())
        .collect();
    files.sort();
    if files.is_empty() {
        bail!("--scans {}: no PLY, PCD, XYZ or CSV file in the folder", dir.display());
    }
    Ok(files)
}
