//! `pficp-sim-board`: the Verilated board top served on a pseudo-terminal, so that
//! `pficp board info --port <path>` and `pficp register --board <path>` talk to it exactly
//! as to a board on a USB-serial port.
//!
//! Prints the device path as the first line of stdout. The board's UART runs at its real
//! bit timing in simulated clocks (the wall-clock rate is whatever Verilator manages, about
//! about a fortieth of real time at 50 MHz). Keeps serving when the host closes and reopens the
//! port; exits cleanly on SIGINT or SIGTERM with a summary on stderr. With `--check` the
//! byte-level reference runs beside the RTL and every byte the board sends is compared;
//! the exit code is 1 if any differed.

use anyhow::{Context, Result};
use clap::Parser;
use pficp::board::pty::PtyLine;
use pficp_fpga::board::BoardConfig;
use pficp_sim::serial::{SerialBoard, LED_BUSY};
use serialport::SerialPort;
use std::io::{ErrorKind, Read, Write};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Parser, Debug)]
#[command(name = "pficp-sim-board", version, about = "Serve the Verilated PF-ICP board on a pseudo-terminal")]
struct Args {
    /// Serve the fast-UART test build (4 lanes, 25 Mbaud) instead of the real board
    /// (8 lanes, 3,000,000 baud at 50 MHz, as hdl-gen generates it).
    #[arg(long)]
    fast: bool,
    /// Run the byte-level reference beside the RTL and compare every byte the board sends
    /// (for a host that waits for each answer, as `pficp` does).
    #[arg(long)]
    check: bool,
    /// Write a VCD of the whole run (large: every clock).
    #[arg(long)]
    vcd: Option<PathBuf>,
    /// Also write the device path to this file (for scripts).
    #[arg(long)]
    path_file: Option<PathBuf>,
    /// Clocks simulated between looks at the pseudo-terminal.
    #[arg(long, default_value_t = 20_000)]
    chunk: u64,
}

fn main() {
    match serve(Args::parse()) {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("pficp-sim-board: error: {e:#}");
            std::process::exit(2);
        }
    }
}

fn serve(args: Args) -> Result<i32> {
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(sig, Arc::clone(&stop)).context("installing the signal handlers")?;
    }
    let config = if args.fast { BoardConfig::FAST_SIM } else { BoardConfig::default() };
    let mut board = SerialBoard::new(config);
    if args.check {
        board = board.with_reference();
    }
    if let Some(v) = &args.vcd {
        board.trace_to(v).with_context(|| format!("opening {}", v.display()))?;
    }
    let mut line = PtyLine::new().context("creating a pseudo-terminal pair")?;
    let path = line.path.clone();
    println!("{path}");
    std::io::stdout().flush().ok();
    if let Some(f) = &args.path_file {
        std::fs::write(f, format!("{path}\n")).with_context(|| format!("writing {}", f.display()))?;
    }
    eprintln!(
        "pficp-sim-board: serving the Verilated board ({} lanes, {} Hz, {} baud = {} clocks per bit{}) on {path}",
        config.lanes,
        config.clock_hz,
        config.baud,
        config.bit_period(),
        if args.check { ", checked against the reference" } else { "" }
    );

    let started = Instant::now();
    let mut buf = [0u8; 4096];
    let mut failure: Option<anyhow::Error> = None;
    line.serve_here(&stop, |master| {
        // Wait for the host only when the board has nothing to do.
        let idle = board.idle();
        if let Err(e) = master.set_timeout(if idle { Duration::from_millis(50) } else { Duration::from_millis(0) }) {
            failure = Some(anyhow::Error::from(e).context("setting the pseudo-terminal's timeout"));
            return false;
        }
        match master.read(&mut buf) {
            Ok(n) => board.send(&buf[..n]),
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted) => {}
            Err(e) => {
                failure = Some(anyhow::Error::from(e).context("reading the pseudo-terminal"));
                return false;
            }
        }
        if idle && board.idle() {
            return true;
        }
        for _ in 0..args.chunk {
            board.step();
        }
        let out = board.take_received();
        if !out.is_empty() {
            if let Err(e) = master.write_all(&out) {
                failure = Some(anyhow::Error::from(e).context("writing the pseudo-terminal"));
                return false;
            }
            master.flush().ok();
        }
        true
    });
    if let Some(e) = failure {
        return Err(e);
    }

    let (sent, received) = board.byte_counts();
    let (compared, mismatch) = board.comparison();
    let secs = started.elapsed().as_secs_f64();
    eprintln!(
        "pficp-sim-board: stopped: {} clocks ({:.3} s at {} MHz) in {secs:.1} s, {sent} bytes in, {received} bytes out, leds {:04b}{}",
        board.clocks(),
        board.clocks() as f64 / config.clock_hz as f64,
        config.clock_hz / 1_000_000,
        board.pins().leds,
        if board.pins().leds & LED_BUSY != 0 { " (busy)" } else { "" }
    );
    if args.check {
        let pending = board.expected_pending();
        match mismatch {
            None if pending == 0 => {
                eprintln!(
                    "pficp-sim-board: check: {compared} bytes compared with the reference, all equal, none pending; \
                     {} running Status replies within the progress rule; LEDs by their rule",
                    board.progress_frames()
                );
                Ok(0)
            }
            None => {
                eprintln!(
                    "pficp-sim-board: check: MISMATCH: the reference has {pending} bytes the board never sent \
                     ({compared} bytes compared, none differed)"
                );
                Ok(1)
            }
            Some(m) => {
                eprintln!("pficp-sim-board: check: MISMATCH: {m} ({compared} bytes compared)");
                Ok(1)
            }
        }
    } else {
        Ok(0)
    }
}
