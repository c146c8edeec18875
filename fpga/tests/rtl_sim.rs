//! The rust_hdl RTL against the cycle-accurate reference, clock by clock, in rust_hdl's own
//! simulator; and checks of the generated Verilog.
#![cfg(feature = "rtl")]

use pficp_fpga::format::{pack_point, FxPoint, FxPose};
use pficp_fpga::pipeline::{Inputs, Outputs, PipelineModel};
use pficp_fpga::rtl::{pipeline_verilog, pose_word, NnPipeline, MUL18_MODULE, SUPPORTED_LANES};
use rust_hdl::prelude::*;

/// What the driver does on a clock, given the reference's outputs before the edge.
#[derive(Clone, Debug)]
enum Step {
    /// Write a model point.
    Write(u16, FxPoint),
    /// Nothing (all inputs low, data buses noisy).
    Idle,
    /// Start a particle, then stream `scan` (with a gap every third clock if `gaps`), with a
    /// spurious `start` while busy, until `cost_valid`; if `writes`, also overwrite model
    /// words while busy (read-first collisions with the sweep included).
    Particle { count: u16, pose: FxPose, scan: Vec<FxPoint>, gaps: bool, writes: bool },
}

/// A cheap deterministic generator.
fn lcg(seed: &mut u64) -> u64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *seed >> 33
}

/// Expand the script into per-clock inputs, driven by the reference (the RTL must take a
/// point exactly when the reference does, which the per-clock comparison checks).
struct Driver {
    script: Vec<Step>,
    at: usize,
    phase: usize,
    next_point: usize,
    clock_in_step: u64,
    seed: u64,
}

impl Driver {
    fn new(script: Vec<Step>) -> Self {
        Driver { script, at: 0, phase: 0, next_point: 0, clock_in_step: 0, seed: 99 }
    }

    fn done(&self) -> bool {
        self.at >= self.script.len()
    }

    /// Inputs for the next edge, given the reference's outputs now.
    fn inputs(&mut self, now: &Outputs) -> Inputs {
        let noise = lcg(&mut self.seed) | (lcg(&mut self.seed) << 31);
        let mut i =
            Inputs { scan_data: noise & ((1 << 48) - 1), model_waddr: (noise & 0xfff) as u16, ..Default::default() };
        let Some(step) = self.script.get(self.at).cloned() else { return i };
        self.clock_in_step += 1;
        match step {
            Step::Write(a, p) => {
                i.model_we = true;
                i.model_waddr = a;
                i.model_wdata = pack_point(p);
                self.advance();
            }
            Step::Idle => self.advance(),
            Step::Particle { count, pose, scan, gaps, writes } => {
                if self.phase == 0 {
                    i.start = true;
                    i.pose = pose;
                    i.model_count = count;
                    self.phase = 1;
                    self.next_point = 0;
                } else if now.cost_valid {
                    self.advance();
                } else {
                    // A spurious start while busy (ignored), with a different count and pose.
                    if self.clock_in_step == 4 {
                        i.start = true;
                        i.model_count = count + 1;
                        i.pose = FxPose { m: [1; 9], t: [2; 3] };
                    }
                    if writes && self.clock_in_step % 5 == 2 {
                        i.model_we = true;
                        i.model_waddr = (self.clock_in_step / 5) as u16 % count;
                        i.model_wdata = noise >> 16;
                    }
                    let offer = self.next_point < scan.len() && !(gaps && self.clock_in_step % 3 == 1);
                    if offer {
                        i.scan_valid = true;
                        i.scan_data = pack_point(scan[self.next_point]);
                        i.scan_last = self.next_point + 1 == scan.len();
                        if now.scan_ready {
                            self.next_point += 1;
                        }
                    }
                }
            }
        }
        i
    }

    fn advance(&mut self) {
        self.at += 1;
        self.phase = 0;
        self.clock_in_step = 0;
    }
}

fn set_inputs<const P: usize>(x: &mut NnPipeline<P>, i: &Inputs) {
    x.model_we.next = i.model_we;
    x.model_waddr.next = (i.model_waddr as u64).into();
    x.model_wdata.next = i.model_wdata.into();
    x.model_count.next = (i.model_count as u64).into();
    x.start.next = i.start;
    x.pose.next = pose_word(&i.pose);
    x.scan_valid.next = i.scan_valid;
    x.scan_data.next = i.scan_data.into();
    x.scan_last.next = i.scan_last;
}

fn get_outputs<const P: usize>(x: &NnPipeline<P>) -> Outputs {
    Outputs {
        scan_ready: x.scan_ready.val(),
        busy: x.busy.val(),
        nn_valid: x.nn_valid.val(),
        nn_index: x.nn_index.val().to_u64() as u16,
        nn_dist: x.nn_dist.val().to_u64(),
        cost_valid: x.cost_valid.val(),
        cost: x.cost.val().to_u64(),
        // No such port on the brute-force pipeline; its model leaves it zero.
        nn_point: [0, 0, 0],
    }
}

/// The first differing port, by name.
fn mismatch(got: &Outputs, want: &Outputs) -> Option<String> {
    let ports: [(&str, u64, u64); 7] = [
        ("scan_ready", got.scan_ready as u64, want.scan_ready as u64),
        ("busy", got.busy as u64, want.busy as u64),
        ("nn_valid", got.nn_valid as u64, want.nn_valid as u64),
        ("nn_index", got.nn_index as u64, want.nn_index as u64),
        ("nn_dist", got.nn_dist, want.nn_dist),
        ("cost_valid", got.cost_valid as u64, want.cost_valid as u64),
        ("cost", got.cost, want.cost),
    ];
    let bad: Vec<String> =
        ports.iter().filter(|p| p.1 != p.2).map(|p| format!("{}: rtl {:#x}, reference {:#x}", p.0, p.1, p.2)).collect();
    (!bad.is_empty()).then(|| bad.join("; "))
}

/// What a lockstep run saw.
#[derive(Debug, Default)]
struct Report {
    clocks: u64,
    nn_results: usize,
    costs: Vec<u64>,
    error: Option<String>,
}

/// Run `NnPipeline<P>` and `PipelineModel::new(P)` in lockstep over `script`; compare all
/// output ports after every rising edge (and before the first).
fn lockstep<const P: usize>(script: Vec<Step>) -> Report {
    let report = std::sync::Arc::new(std::sync::Mutex::new(Report::default()));
    let rep = report.clone();
    let mut uut = NnPipeline::<P>::new();
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<NnPipeline<P>>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<NnPipeline<P>>| {
        let mut x = sim.init()?;
        let mut model = PipelineModel::new(P);
        let mut driver = Driver::new(script.clone());
        let mut tail = 0;
        let mut clock = 0u64;
        // The first rising edge, with every input low.
        set_inputs(&mut x, &Inputs::default());
        wait_clock_true!(sim, clock, x);
        model.step(&Inputs::default());
        loop {
            let want = model.outputs();
            let got = get_outputs(&x);
            let mut r = rep.lock().unwrap();
            r.clocks = clock;
            if let Some(m) = mismatch(&got, &want) {
                r.error = Some(format!("P={P}, after edge {clock}: {m}"));
                drop(r);
                return sim.halt(x);
            }
            r.nn_results += want.nn_valid as usize;
            if want.cost_valid {
                r.costs.push(want.cost);
            }
            drop(r);
            if driver.done() {
                tail += 1;
                if tail > 4 {
                    break;
                }
            }
            let i = driver.inputs(&want);
            set_inputs(&mut x, &i);
            wait_clock_cycle!(sim, clock, x);
            model.step(&i);
            clock += 1;
            if clock > 20_000 {
                rep.lock().unwrap().error = Some("runaway".into());
                return sim.halt(x);
            }
        }
        sim.done(x)
    });
    let result = sim.run(Box::new(uut), 500_000);
    let mut r = std::mem::take(&mut *report.lock().unwrap());
    if r.error.is_none() {
        if let Err(e) = result {
            r.error = Some(format!("simulation error: {e:?}"));
        }
    }
    r
}

fn script(seed: u64) -> (Vec<Step>, usize, usize) {
    let mut seed = seed;
    let mut pt =
        |range: i64| -> FxPoint { [0; 3].map(|_: i16| ((lcg(&mut seed) as i64 % (2 * range + 1)) - range) as i16) };
    let mut s = Vec::new();
    // Six model points; a tie (points 1 and 4 equal) and the extreme coordinates.
    let model: Vec<FxPoint> = vec![pt(9000), pt(9000), [i16::MIN, i16::MAX, 0], pt(9000), [0; 3], pt(30000)];
    let model = {
        let mut m = model;
        m[4] = m[1];
        m
    };
    for (a, &p) in model.iter().enumerate() {
        s.push(Step::Write(a as u16, p));
        if a == 2 {
            s.push(Step::Idle);
        }
    }
    let pose = FxPose::from_f64(&[0.9, -0.3, 0.1, 0.3, 0.9, 0.0, -0.1, 0.05, 0.95], &[0.1, -0.2, 0.05]);
    // Five scan points, a gap in the stream; one lands exactly on model point 1/4 (tie).
    let mut scan: Vec<FxPoint> = (0..5).map(|_| pt(8000)).collect();
    scan[2] = [i16::MAX, i16::MIN, i16::MIN];
    let ident = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    s.push(Step::Particle { count: 6, pose, scan: scan.clone(), gaps: true, writes: false });
    let n1 = scan.len();
    // Tie at the identity: scan point = model point 1 (and 4).
    s.push(Step::Particle {
        count: 6,
        pose: ident,
        scan: vec![model[1], scan[0], [i16::MIN; 3]],
        gaps: false,
        writes: false,
    });
    // Overwrite a model point between particles; a saturating pose (scale ~3.9, shift).
    s.push(Step::Write(3, [-4000, 4000, -8000]));
    s.push(Step::Idle);
    let sat = FxPose::from_f64(&[3.9, -3.9, 0.0, 3.9, 3.9, 0.1, 0.0, -2.0, -4.0], &[15.0, -16.0, 1.0]);
    s.push(Step::Particle {
        count: 5,
        pose: sat,
        scan: vec![scan[1], scan[3], [i16::MAX; 3], [-1, 1, -1]],
        gaps: false,
        writes: false,
    });
    s.push(Step::Idle);
    (s, n1 + 3 + 4, 3)
}

/// 40 random model points, then particles of assorted sizes (1 model point; scans that do
/// and do not fill the last batch), random poses, gaps, model writes while busy.
fn random_script(seed: u64) -> (Vec<Step>, usize, usize) {
    let mut seed = seed;
    let mut rnd = |range: i64| (lcg(&mut seed) as i64 % (2 * range + 1)) - range;
    let mut s = Vec::new();
    for a in 0..40 {
        s.push(Step::Write(a, [0; 3].map(|_: i16| rnd(30000) as i16)));
    }
    let (mut results, mut costs) = (0, 0);
    for (count, n_scan, gaps, writes) in
        [(40, 9, false, false), (1, 3, true, false), (17, 8, true, true), (40, 16, false, false), (33, 5, false, true)]
    {
        let m: [f64; 9] = std::array::from_fn(|_| rnd(1200) as f64 / 1000.0);
        let t: [f64; 3] = std::array::from_fn(|_| rnd(500) as f64 / 1000.0);
        let scan: Vec<FxPoint> = (0..n_scan).map(|_| [0; 3].map(|_: i16| rnd(20000) as i16)).collect();
        s.push(Step::Particle { count, pose: FxPose::from_f64(&m, &t), scan, gaps, writes });
        results += n_scan;
        costs += 1;
    }
    (s, results, costs)
}

fn check<const P: usize>((s, n_results, n_costs): (Vec<Step>, usize, usize)) {
    let t = std::time::Instant::now();
    let r = lockstep::<P>(s);
    eprintln!(
        "P={P}: {} clocks compared in {:.2?}, {} nn results, costs {:?}",
        r.clocks,
        t.elapsed(),
        r.nn_results,
        r.costs
    );
    assert!(r.error.is_none(), "{}", r.error.unwrap());
    assert_eq!(r.nn_results, n_results, "P={P}: every scan point's result was presented");
    assert_eq!(r.costs.len(), n_costs, "P={P}: every particle finished");
    assert!(r.clocks > 50);
}

#[test]
fn lockstep_one_lane() {
    check::<1>(script(7));
}

#[test]
fn lockstep_two_lanes() {
    check::<2>(script(7));
    check::<2>(random_script(11));
}

#[test]
fn lockstep_four_lanes() {
    check::<4>(script(7));
    check::<4>(random_script(12));
}

#[test]
fn lockstep_sixteen_lanes() {
    check::<16>(random_script(13));
}

#[test]
fn verilog_validates_in_yosys() {
    let v = pipeline_verilog(2);
    yosys_validate("pficp_nn_pipeline_2", &v).unwrap();
}

#[test]
fn verilog_16_lanes_has_top_and_one_multiplier_module() {
    let v = pipeline_verilog(16);
    assert!(v.contains("module top("), "top module");
    let defs = v.matches(&format!("module {MUL18_MODULE}(")).count();
    assert_eq!(defs, 1, "the multiplier module is defined exactly once");
    // 9 transform multipliers + 3 per lane.
    assert_eq!(v.matches(&format!("{MUL18_MODULE} u_mul(")).count(), 9 + 3 * 16);
    let flat = v.split_whitespace().collect::<Vec<_>>().join(" ");
    for port in [
        "input wire clock;",
        "input wire model_we;",
        "input wire [11:0] model_waddr;",
        "input wire [47:0] model_wdata;",
        "input wire [12:0] model_count;",
        "input wire start;",
        "input wire [215:0] pose;",
        "input wire scan_valid;",
        "input wire [47:0] scan_data;",
        "input wire scan_last;",
        "output reg scan_ready;",
        "output reg busy;",
        "output reg nn_valid;",
        "output reg [11:0] nn_index;",
        "output reg [33:0] nn_dist;",
        "output reg cost_valid;",
        "output reg [47:0] cost;",
    ] {
        assert!(flat.contains(port), "port `{port}`");
    }
    if let Ok(dir) = std::env::var("CARGO_TARGET_TMPDIR") {
        let _ = std::fs::write(std::path::Path::new(&dir).join("nn_pipeline_16.v"), &v);
    }
}

#[test]
fn every_supported_lane_count_generates() {
    for p in SUPPORTED_LANES {
        assert!(pipeline_verilog(p).contains("module top("), "P={p}");
    }
}

#[test]
#[should_panic(expected = "not supported")]
fn unsupported_lane_count_panics() {
    pipeline_verilog(3);
}

/// The reference alone over `script`: per edge, the inputs and the outputs after it.
fn reference_trace(lanes: usize, script: Vec<Step>) -> Vec<(Inputs, Outputs)> {
    let mut model = PipelineModel::new(lanes);
    let mut driver = Driver::new(script);
    let mut trace = Vec::new();
    let mut tail = 0;
    while tail < 5 {
        if driver.done() {
            tail += 1;
        }
        let i = driver.inputs(&model.outputs());
        model.step(&i);
        trace.push((i, model.outputs()));
        assert!(trace.len() < 20_000, "runaway");
    }
    trace
}

/// C++ driver of the Verilated `top`: per line of trace.txt, set the inputs with the clock
/// low, raise the clock, compare the outputs with the reference's.
const VERILATOR_MAIN: &str = r#"
#include "Vtop.h"
#include "verilated.h"
#include <cstdio>
#include <cstring>
typedef unsigned long long u64;
static unsigned hexval(char c) { return c <= '9' ? c - '0' : (c | 32) - 'a' + 10; }
int main(int argc, char** argv) {
  VerilatedContext* ctx = new VerilatedContext;
  ctx->commandArgs(argc, argv);
  Vtop* t = new Vtop(ctx);
  FILE* f = fopen("trace.txt", "r");
  if (!f) { printf("no trace\n"); return 1; }
  char pose[128];
  u64 we, waddr, wdata, count, start, sv, sd, sl, er, eb, env, eidx, edist, ecv, ecost;
  long edges = 0, errors = 0;
  t->clock = 0;
  t->eval();
  while (fscanf(f, "%llx %llx %llx %llx %llx %127s %llx %llx %llx %llx %llx %llx %llx %llx %llx %llx", &we, &waddr,
                &wdata, &count, &start, pose, &sv, &sd, &sl, &er, &eb, &env, &eidx, &edist, &ecv, &ecost) == 16) {
    t->model_we = we; t->model_waddr = waddr; t->model_wdata = wdata; t->model_count = count;
    t->start = start; t->scan_valid = sv; t->scan_data = sd; t->scan_last = sl;
    int n = strlen(pose);
    for (int w = 0; w < 7; ++w) {
      unsigned v = 0;
      for (int k = 7; k >= 0; --k) { int at = n - 1 - (8 * w + k); v = (v << 4) | (at >= 0 ? hexval(pose[at]) : 0); }
      t->pose[w] = v;
    }
    t->pose[6] &= 0xffffff;
    t->clock = 0; t->eval();
    t->clock = 1; t->eval();
    u64 got[7] = {t->scan_ready, t->busy, t->nn_valid, t->nn_index, t->nn_dist, t->cost_valid, t->cost};
    u64 want[7] = {er, eb, env, eidx, edist, ecv, ecost};
    if (memcmp(got, want, sizeof got)) {
      if (errors < 10) {
        printf("MISMATCH edge %ld:", edges);
        for (int k = 0; k < 7; ++k) printf(" %llx/%llx", got[k], want[k]);
        printf("\n");
      }
      ++errors;
    }
    ++edges;
  }
  printf("RESULT %ld edges %ld errors\n", edges, errors);
  t->final();
  delete t;
  delete ctx;
  return 0;
}
"#;

fn pose_hex(p: &FxPose) -> String {
    let w = p.pack();
    format!("{:06x}{:016x}{:016x}{:016x}", w[3], w[2], w[1], w[0])
}

/// The generated Verilog (not the rust_hdl model) against the reference, every edge, with
/// Verilator and a C++ driver (fails, never skips, when `verilator` is not installed).
#[test]
fn verilator_runs_the_script_like_the_reference() {
    assert!(
        std::process::Command::new("verilator").arg("--version").output().is_ok(),
        "verilator not found: install it with `apt-get install -y verilator yosys` (tests/run-all does)"
    );
    for lanes in [2usize, 4, 16] {
        let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("verilator_nn_{lanes}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("top.v"), pipeline_verilog(lanes)).unwrap();
        std::fs::write(dir.join("main.cpp"), VERILATOR_MAIN).unwrap();
        let mut steps = script(7).0;
        steps.extend(random_script(lanes as u64).0);
        let trace = reference_trace(lanes, steps);
        let mut text = String::new();
        for (i, o) in &trace {
            text += &format!(
                "{:x} {:x} {:x} {:x} {:x} {} {:x} {:x} {:x} {:x} {:x} {:x} {:x} {:x} {:x} {:x}\n",
                i.model_we as u8,
                i.model_waddr,
                i.model_wdata,
                i.model_count,
                i.start as u8,
                pose_hex(&i.pose),
                i.scan_valid as u8,
                i.scan_data,
                i.scan_last as u8,
                o.scan_ready as u8,
                o.busy as u8,
                o.nn_valid as u8,
                o.nn_index,
                o.nn_dist,
                o.cost_valid as u8,
                o.cost
            );
        }
        std::fs::write(dir.join("trace.txt"), text).unwrap();
        let build = std::process::Command::new("verilator")
            .current_dir(&dir)
            .args(["--cc", "--exe", "--build", "-j", "2", "-Wno-fatal", "-Wno-WIDTH", "-Wno-DECLFILENAME"])
            .args(["--top-module", "top", "top.v", "main.cpp", "-o", "sim"])
            .output()
            .unwrap();
        assert!(build.status.success(), "verilator: {}", String::from_utf8_lossy(&build.stderr));
        let run = std::process::Command::new(dir.join("obj_dir/sim")).current_dir(&dir).output().unwrap();
        let out = String::from_utf8_lossy(&run.stdout);
        eprintln!("P={lanes}: {}", out.lines().filter(|l| l.starts_with("RESULT")).collect::<String>());
        assert!(out.contains(&format!("RESULT {} edges 0 errors", trace.len())), "P={lanes}:\n{out}");
    }
}
