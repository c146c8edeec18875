//! `pficp register`: one registration, in software or with the board.

use crate::args::*;
use crate::load;
use anyhow::Result;
use pficp::cli::{Inputs, Provenance, RegisterReport, Settings};
use pficp::io::{format_from_path, write_cloud};
use pficp::progress::{note, Progress};
use pficp::request::{BoardProgress, BoardRun, Engine, Registered, Request};

pub(crate) fn register(a: &RegisterArgs) -> Result<()> {
    let settings = a.pf.settings()?;
    let method = a.method;
    let model = load(&a.model, "model")?;
    let scan = load(&a.scan, "scan")?;
    if let Some(out) = &a.out_aligned {
        format_from_path(out)?;
    }
    let engine = Engine::from_options(a.board.is_some(), a.host_driven, a.board_points)?;
    let request = Request { method, engine, settings };
    request.check(&model, &scan)?;
    // Open the port before the work starts: a missing or silent board fails at once.
    let mut client = a.board.as_deref().map(|port| a.link.open(port)).transpose()?;
    note(format_args!("registering {} scan points to {} model points with {}", scan.len(), model.len(), method.name()));
    let progress = BoardProgress { on_board: &mut on_board_progress() };
    let Registered { outcome, board } = request.run(&model, &scan, client.as_mut(), progress)?;
    match &board {
        Some(BoardRun::OnBoard(b)) => note(format_args!(
            "board: {} model points{}, {} scan points, {} iterations on the board (best cost {:.3e}), \
             {} Status polls, modelled board time {:.3} s, {} requests, {} resends",
            b.model_points,
            if b.model_subsampled { " (subsampled)" } else { "" },
            b.scan_points,
            b.result.iterations,
            b.cost_msd,
            b.polls,
            b.modelled.as_secs_f64(),
            b.stats.requests,
            b.stats.resends + b.stats.restarts
        )),
        Some(BoardRun::HostDriven(b)) => note(format_args!(
            "board: {} model points{}, {} scan points, {} iterations weighed, {} requests, {} resends",
            b.model_points,
            if b.model_subsampled { " (subsampled)" } else { "" },
            b.scan_points,
            b.iterations,
            b.stats.requests,
            b.stats.resends + b.stats.restarts
        )),
        None => {}
    }
    if let Some(pf) = &outcome.pf {
        let t = &pf.times;
        // The rescue runs only when the evidence ruled out the first answer.
        let rescue = if t.rescue.is_zero() {
            String::new()
        } else {
            format!(", rescue search {:.3} s (the first answer was ruled out)", t.rescue.as_secs_f64())
        };
        note(format_args!(
            "stages: clustering {:.3} s, covariance {:.3} s, filter {:.3} s, polish {:.3} s{rescue}",
            t.clustering.as_secs_f64(),
            t.covariance.as_secs_f64(),
            t.filter.as_secs_f64(),
            t.polish.as_secs_f64()
        ));
    }
    let registered = Registered { outcome, board };
    let mut report = RegisterReport::of(&request, &registered, a.board.as_deref());
    let inputs = Inputs {
        model: a.model.display().to_string(),
        scan: a.scan.display().to_string(),
        model_points: model.len(),
        scan_points: scan.len(),
    };
    let recorded = Settings::of(&request);
    report = report.produced_by(Provenance::new(method.name(), inputs, recorded, a.board.as_deref(), a.host_driven));
    if a.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print!("{}", report.text());
    }
    if let Some(out) = &a.out_aligned {
        let aligned = registered.outcome.registration.pose.apply_all(scan.points());
        write_cloud(out, &aligned, format_from_path(out)?)?;
        note(format_args!("wrote the aligned scan to {}", out.display()));
    }
    Ok(())
}

/// Upload progress on stderr: a bar per store on a terminal, one line per finished store
/// ([`pficp::progress`]).
pub(crate) fn upload_progress() -> impl FnMut(pficp::board::Upload, usize, usize) + Send {
    let mut bar: Option<Progress> = None;
    move |store, done, total| {
        // The model goes with its cell table (protocol 3), counted in data bytes.
        let unit = if store == pficp::board::Upload::Model { "bytes" } else { "points" };
        let b =
            bar.get_or_insert_with(|| Progress::bar(&format!("uploading the {}", store.name()), total as u64, unit));
        b.set(done as u64);
        if done == total {
            if let Some(b) = bar.take() {
                b.finish(format_args!("uploaded the {}: {total} {unit}", store.name()));
            }
        }
    }
}

/// A board registration's progress on stderr (either mode): the uploads as [`upload_progress`],
/// then a bar over the filter's iterations (one line when it is done).
pub(crate) fn on_board_progress() -> impl FnMut(pficp::board::on_board::OnBoardStep, usize, usize) + Send {
    use pficp::board::on_board::OnBoardStep;
    let mut uploads = upload_progress();
    let mut filter: Option<Progress> = None;
    move |step, done, total| match step {
        OnBoardStep::Upload(store) => uploads(store, done, total),
        OnBoardStep::Resident => {
            note(format_args!("the board holds the model already (its digest matches): not uploaded"))
        }
        OnBoardStep::Filter => {
            let b = filter.get_or_insert_with(|| Progress::bar("filter on the board", total as u64, "iterations"));
            b.set(done as u64);
            if done == total {
                if let Some(b) = filter.take() {
                    b.finish("filter on the board: done");
                }
            }
        }
    }
}
