//! The board mode against the software mode (issue 13's accuracy rule): on models 1 to 3
//! (the success-rate experiment, `pficp eval --board-reference`: random transforms, both
//! noise levels) and on the realistic benchmark (`pficp eval --suite realistic
//! --board-reference`), the successes of
//! - `pf-icp`, the software mode;
//! - `pf-icp-board-filter`, the board's pose alone (its filter and its on-board polish, by
//!   the bit-exact reference: what the board returns);
//! - `pf-icp-board`, that pose after the host's polish (`pficp register --board`).
//!
//! Each board column must be within 2 percentage points of the software's success on each
//! set. Slow (a few minutes): ignored by default. Run it with
//! `cargo test --release -p pficp-host --test board_accuracy -- --ignored --nocapture`
//! (`PFICP_TRIALS` random transforms a row, default 30; `PFICP_CASES` cases a family,
//! default 8, the quick set; `PFICP_SPLIT=test` for the held-out split, default dev). The
//! figures are in docs/on-board-polish.md, "Accuracy".

use pficp::eval::realistic::{self, Family, RealisticOptions, Split};
use pficp::eval::{success, EvalOptions, BOARD_COLUMN, BOARD_FILTER_COLUMN};
use pficp::registration::methods::Method;

fn env_or(name: &str, default: usize) -> usize {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Successes of each column over a set, in the order software, board alone, board + host
/// polish, and the set's size.
type Counts = ([usize; 3], usize);

const COLUMNS: [&str; 3] = ["pf-icp", BOARD_FILTER_COLUMN, BOARD_COLUMN];

fn models() -> Counts {
    let opts = EvalOptions {
        trials: env_or("PFICP_TRIALS", 30),
        methods: vec![Method::PfIcp],
        board: true,
        tables: false,
        plots: false,
        ..Default::default()
    };
    let report = success::run(&opts).expect("the success rates");
    println!("{}", report.render());
    tally(
        report
            .rows
            .iter()
            .map(|r| (r.cells.iter().map(|c| (c.method.as_str(), c.successes)).collect(), r.cells[0].trials)),
    )
}

fn realistic_set() -> Counts {
    let split = if std::env::var("PFICP_SPLIT").is_ok_and(|v| v == "test") { Split::Test } else { Split::Dev };
    let opts = RealisticOptions {
        cases: env_or("PFICP_CASES", 8),
        split,
        families: Family::PLANE_CUT.to_vec(),
        methods: vec![Method::PfIcp],
        board: true,
        progress: false,
        ..Default::default()
    };
    let report = realistic::run(&opts).expect("the realistic benchmark");
    print!("{}", report.render());
    tally(
        report
            .families
            .iter()
            .map(|f| (f.cells.iter().map(|c| (c.method.as_str(), c.successes)).collect(), f.cells[0].cases)),
    )
}

/// [`COLUMNS`]' successes and the cases over rows of (each column's name and successes, the
/// row's cases).
fn tally<'a>(rows: impl Iterator<Item = (Vec<(&'a str, usize)>, usize)>) -> Counts {
    let mut counts = [0; 3];
    let mut total = 0;
    for (cells, cases) in rows {
        for (k, name) in COLUMNS.iter().enumerate() {
            counts[k] += cells.iter().find(|c| c.0 == *name).expect("a column").1;
        }
        total += cases;
    }
    (counts, total)
}

#[test]
#[ignore = "a few minutes in release; prints the figures of docs/on-board-polish.md"]
fn the_board_mode_is_as_good_as_the_software_mode() {
    let mut failures = Vec::new();
    for (set, (counts, total)) in [("models 1-3", models()), ("realistic", realistic_set())] {
        let pct = |c: usize| 100.0 * c as f64 / total as f64;
        println!(
            "{set}: software {}/{total} ({:.1}%), board alone {}/{total} ({:.1}%), board + host polish {}/{total} ({:.1}%)",
            counts[0],
            pct(counts[0]),
            counts[1],
            pct(counts[1]),
            counts[2],
            pct(counts[2])
        );
        for k in 1..3 {
            if pct(counts[k]) < pct(counts[0]) - 2.0 {
                failures.push(format!(
                    "{set}: {} {:.1}% against the software's {:.1}%",
                    COLUMNS[k],
                    pct(counts[k]),
                    pct(counts[0])
                ));
            }
        }
    }
    assert!(failures.is_empty(), "more than 2 points behind: {failures:?}");
}
