//! Builds the Verilator models of the generated designs: every entry of the registry
//! `pficp_fpga::designs::DESIGNS` (name, Verilator prefix, Verilog generator, parameters,
//! ports), the neighbour pipeline, the weight stage, the surface residual, the polish's
//! datapath, bench and unit, the sequencer, and the board top in its default and fast-UART
//! configurations;
//!
//! the lane-parametrised ones for every `P` in [`DEFAULT_LANES`] (or `PFICP_SIM_LANES=4,16`).
//! Per model, on a pool of `NUM_JOBS` threads, largest first:
//!
//! 1. the Verilog, from the build-dependency `pficp-fpga` (feature `rtl`);
//! 2. `verilator --cc --trace --prefix <prefix>` (C++ in `$OUT_DIR/<prefix lower case>/`);
//! 3. the shim: the checked-in template `cpp/shim.h` (create, free, tick, VCD open, flush
//!    and close, templated on the Verilated class) instantiated for `<prefix>` by
//!    `PFICP_SHIM`, and the port copies generated from the `VL_IN*/VL_OUT*` port lines of
//!    `<prefix>.h` after checking them against the design's ports (the registry's, the one
//!    list the wrappers also take their compared outputs from): `set_inputs`
//!    (a packed `u64` array, masked to the port widths) and `get_outputs`;
//! 4. one unity file compiled with the `cc` compiler and flags at `-O2`, but with the
//!    run-once code (most of the source) after a pragma that turns optimisation off:
//!    half the compile time of Verilator's makefile build, the same simulation speed.
//!
//! Then the Verilator runtime (`verilated.o`, `verilated_threads.o`, `verilated_vcd_c.o`),
//! built once with a generated makefile and cached in `target/verilator-runtime/<key>/` (the
//! objects depend only on the Verilator version and the flags, not on the design); one static
//! archive (models + shims + runtime) via `cc`; and `$OUT_DIR/models.rs`, the Rust
//! declarations and the table of models, included by `src/lib.rs`.
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use pficp_fpga::board::BoardConfig;

/// Lane counts verilated unless `PFICP_SIM_LANES` says otherwise: 4 for fast tests, 16 (the
/// design point).
const DEFAULT_LANES: [usize; 2] = [4, 16];

// Every design, its generator and its ports: the registry `pficp_fpga::designs`.
use pficp_fpga::designs::{Design, Params, Port, DESIGNS};

/// Optimisation of a model's per-clock code (Verilator's `VM_*_FAST` files) and the shim.
const OPT_MODEL: &str = "-O2";
/// Turns optimisation off for the rest of a translation unit (the run-once code, Verilator's
/// `VM_*_SLOW` files): GCC and Clang; other compilers ignore it and optimise everything.
const UNOPTIMISED: &str = "#if defined(__clang__)\n#pragma clang optimize off\n#elif defined(__GNUC__)\n\
                           #pragma GCC optimize(\"O0\")\n#endif\n";
/// Make flags for the runtime.
const OPT_RUNTIME: &str = "OPT_GLOBAL=-O2";
const RUNTIME_OBJECTS: [&str; 3] = ["verilated.o", "verilated_threads.o", "verilated_vcd_c.o"];

fn run(cmd: &mut Command, what: &str) {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: cannot run {cmd:?}: {e}"));
    if !out.status.success() {
        panic!(
            "{what} failed ({}): {cmd:?}\n--- stdout ---\n{}\n--- stderr ---\n{}",
            out.status,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// `verilator --version`, or a build failure that says how to install it.
fn verilator_version() -> String {
    match Command::new("verilator").arg("--version").output() {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout).trim().to_string(),
        Ok(o) => panic!(
            "pficp-sim needs Verilator 5: `verilator --version` failed ({}): {}",
            o.status,
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(e) => panic!(
            "pficp-sim needs Verilator 5 on PATH ({e}). Install it: apt-get install -y verilator \
             (Debian/Ubuntu), or set PATH to a Verilator 5 build."
        ),
    }
}

/// `$VERILATOR_ROOT/include` as the installed Verilator reports it.
fn verilator_include() -> PathBuf {
    let o = Command::new("verilator").args(["--getenv", "VERILATOR_ROOT"]).output().expect("verilator --getenv");
    let root = String::from_utf8_lossy(&o.stdout).trim().to_string();
    let inc = PathBuf::from(&root).join("include");
    assert!(inc.join("verilated.h").exists(), "no verilated.h under {} (VERILATOR_ROOT = {root:?})", inc.display());
    inc
}

/// FNV-1a (stable across Rust versions, unlike `DefaultHasher`).
fn fnv1a(parts: &[&str]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for p in parts {
        for b in p.bytes().chain(std::iter::once(0)) {
            h ^= b as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
    }
    h
}

/// `target/` from `target/<profile>/build/pficp-sim-<hash>/out`, if the layout is the usual one.
fn target_dir(out: &Path) -> Option<PathBuf> {
    let t = out.ancestors().nth(4)?;
    t.join("CACHEDIR.TAG").exists().then(|| t.to_path_buf())
}

/// A port as the Verilated header declares it.
#[derive(Debug)]
struct HeaderPort {
    input: bool,
    name: String,
    width: usize,
    /// 32-bit words of a `VlWide` port (> 64 bits), else 0.
    words: usize,
}

/// Parse `VL_IN8(&clock,0,0);`, `VL_OUT64(&cost,47,0);`, `VL_INW(&pose,215,0,7);` lines.
fn parse_ports(hdr: &str) -> Vec<HeaderPort> {
    let mut ports = vec![];
    for line in hdr.lines() {
        let l = line.trim();
        let (input, rest) = if let Some(r) = l.strip_prefix("VL_IN") {
            (true, r)
        } else if let Some(r) = l.strip_prefix("VL_OUT") {
            (false, r)
        } else {
            continue;
        };
        let Some(open) = rest.find("(&") else { continue };
        let args: Vec<&str> = rest[open + 2..].trim_end_matches(';').trim_end_matches(')').split(',').collect();
        let num = |s: &str| -> usize { s.trim().parse().unwrap_or_else(|_| panic!("cannot parse port line {l:?}")) };
        let (msb, lsb) = (num(args[1]), num(args[2]));
        let words = if args.len() > 3 { num(args[3]) } else { 0 };
        ports.push(HeaderPort { input, name: args[0].trim().to_string(), width: msb - lsb + 1, words });
    }
    ports
}

/// The header's ports must be exactly `design`'s; returns them in the design's order.
fn check_ports(parsed: Vec<HeaderPort>, design: &Design, header: &Path) -> Vec<HeaderPort> {
    let mut problems = vec![];
    for &Port { name, input, width } in design.ports {
        match parsed.iter().find(|p| p.name == name) {
            None => problems.push(format!("missing port {name}")),
            Some(p) if p.input != input || p.width != width => problems.push(format!(
                "port {name}: expected {} [{}:0], the Verilog has {} [{}:0]",
                if input { "input" } else { "output" },
                width - 1,
                if p.input { "input" } else { "output" },
                p.width - 1
            )),
            Some(p) if (p.width > 64) != (p.words > 0) || (p.words > 0 && p.words != p.width.div_ceil(32)) => {
                problems.push(format!("port {name}: unexpected VlWide word count {}", p.words))
            }
            Some(_) => {}
        }
    }
    for p in &parsed {
        if !design.ports.iter().any(|q| q.name == p.name) {
            problems.push(format!("unexpected port {}", p.name));
        }
    }
    if !problems.is_empty() {
        panic!("the ports of {} do not match {}:\n  {}", header.display(), design.spec, problems.join("\n  "));
    }
    let mut parsed = parsed;
    design
        .ports
        .iter()
        .map(|q| {
            let k = parsed.iter().position(|p| p.name == q.name).unwrap();
            parsed.swap_remove(k)
        })
        .collect()
}

fn mask(bits: usize) -> u64 {
    if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    }
}

/// The C++ shim of one model: the checked-in template (sim/cpp/shim.h) instantiated for
/// the model's class, and its port copies; returns (input u64 words, output u64 words).
fn gen_shim(prefix: &str, ports: &[HeaderPort], cpp: &Path) -> (usize, usize) {
    let f = prefix.to_lowercase();
    let mut c = format!(
        "// Generated by sim/build.rs from {prefix}.h: do not edit (the shim is sim/cpp/shim.h).\n\
         #include \"{prefix}.h\"\n#include \"shim.h\"\nPFICP_SHIM({prefix}, {f})\nextern \"C\" {{\n"
    );
    // Inputs: one u64 per port of <= 64 bits, ceil(width / 64) little-endian u64 for wider
    // ports; every value masked to the port width (Verilator needs clean upper bits).
    writeln!(c, "void pficp_{f}_set_inputs(void* p, const uint64_t* in) {{").unwrap();
    writeln!(c, "  {prefix}* t = pficp::top<{prefix}>(p);").unwrap();
    let mut k = 0;
    for p in ports.iter().filter(|p| p.input && p.name != "clock") {
        let n = &p.name;
        if p.words == 0 {
            writeln!(c, "  t->{n} = in[{k}] & 0x{:x}ULL;", mask(p.width)).unwrap();
            k += 1;
        } else {
            for i in 0..p.words {
                let bits = (p.width - 32 * i).min(32);
                writeln!(c, "  t->{n}[{i}] = (uint32_t)(in[{}] >> {}) & 0x{:x}u;", k + i / 2, 32 * (i % 2), mask(bits))
                    .unwrap();
            }
            k += p.width.div_ceil(64);
        }
    }
    writeln!(c, "}}").unwrap();
    let n_in = k;
    writeln!(c, "void pficp_{f}_get_outputs(void* p, uint64_t* out) {{").unwrap();
    writeln!(c, "  const {prefix}* t = pficp::top<{prefix}>(p);").unwrap();
    let mut k = 0;
    for p in ports.iter().filter(|p| !p.input) {
        if p.words == 0 {
            writeln!(c, "  out[{k}] = (uint64_t)t->{};", p.name).unwrap();
            k += 1;
        } else {
            // Wide outputs: ceil(width / 64) little-endian u64 words.
            for w in 0..p.width.div_ceil(64) {
                let hi = if 2 * w + 1 < p.words {
                    format!(" | ((uint64_t)t->{}[{}] << 32)", p.name, 2 * w + 1)
                } else {
                    String::new()
                };
                writeln!(c, "  out[{k}] = (uint64_t)t->{}[{}]{hi};", p.name, 2 * w).unwrap();
                k += 1;
            }
        }
    }
    writeln!(c, "}}\n}}").unwrap();
    std::fs::write(cpp, c).unwrap();
    (n_in, k)
}

/// The runtime objects: from the cache, or built with `mdir`'s makefile and cached.
fn runtime_objects(mdir: &Path, prefix: &str, out: &Path, key: u64) -> Vec<PathBuf> {
    let cache = target_dir(out).map(|t| t.join("verilator-runtime").join(format!("{key:016x}")));
    if let Some(c) = &cache {
        let objs: Vec<PathBuf> = RUNTIME_OBJECTS.iter().map(|o| c.join(o)).collect();
        if objs.iter().all(|o| o.exists()) {
            return objs;
        }
    }
    run(
        Command::new("make")
            .arg("-C")
            .arg(mdir)
            .args(["-j", "2", "-f", &format!("{prefix}.mk"), OPT_RUNTIME])
            .args(RUNTIME_OBJECTS),
        "building the Verilator runtime",
    );
    let built: Vec<PathBuf> = RUNTIME_OBJECTS.iter().map(|o| mdir.join(o)).collect();
    let Some(c) = cache else { return built };
    // Publish atomically: copy into a private directory, then rename it into place (a
    // concurrent build that won the race leaves its identical copy).
    let tmp = c.with_extension(format!("tmp{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let ok = std::fs::create_dir_all(&tmp).is_ok()
        && built.iter().all(|b| std::fs::copy(b, tmp.join(b.file_name().unwrap())).is_ok())
        && (std::fs::rename(&tmp, &c).is_ok() || c.join(RUNTIME_OBJECTS[2]).exists());
    let _ = std::fs::remove_dir_all(&tmp);
    if ok {
        RUNTIME_OBJECTS.iter().map(|o| c.join(o)).collect()
    } else {
        built
    }
}

fn lanes_to_build() -> Vec<usize> {
    println!("cargo:rerun-if-env-changed=PFICP_SIM_LANES");
    let Ok(s) = std::env::var("PFICP_SIM_LANES") else { return DEFAULT_LANES.to_vec() };
    let mut lanes: Vec<usize> = s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|x| !x.is_empty())
        .map(|x| x.parse().unwrap_or_else(|_| panic!("PFICP_SIM_LANES={s:?}: expected lane counts like 4,16")))
        .collect();
    lanes.sort_unstable();
    lanes.dedup();
    for &p in &lanes {
        assert!(
            pficp_fpga::common::rtl::BOARD_LANES.contains(&p),
            "PFICP_SIM_LANES: {p} lanes is not one of {:?}",
            pficp_fpga::common::rtl::BOARD_LANES
        );
    }
    assert!(!lanes.is_empty(), "PFICP_SIM_LANES is empty");
    lanes
}

/// Built for every lane count.
fn per_lane(design: &Design) -> bool {
    matches!(design.params, Params::Lanes)
}

/// One model to build: a design at a lane count (0 for a design without lanes).
struct Job {
    design: &'static Design,
    lanes: usize,
    prefix: String,
}

/// What building a [`Job`] produced.
struct Built {
    mdir: PathBuf,
    /// The objects of the model and its shim.
    objects: Vec<PathBuf>,
    /// `extern "C"` declarations of the shim.
    decls: String,
    /// The `Model { .. }` entry.
    entry: String,
    report: String,
    seconds: f64,
}

/// The model's C++ files from `<prefix>_classes.mk`: (`VM_CLASSES_FAST` + `VM_SUPPORT_FAST`,
/// `VM_CLASSES_SLOW` + `VM_SUPPORT_SLOW`); every `<prefix>*.cpp` in `mdir` must be in one.
fn class_files(mdir: &Path, prefix: &str) -> (Vec<PathBuf>, Vec<PathBuf>) {
    let mk_path = mdir.join(format!("{prefix}_classes.mk"));
    let mk = std::fs::read_to_string(&mk_path).unwrap();
    let (mut fast, mut slow) = (vec![], vec![]);
    let mut into: Option<bool> = None;
    for line in mk.lines() {
        if let Some(var) = line.strip_suffix(" += \\") {
            into = match var {
                "VM_CLASSES_FAST" | "VM_SUPPORT_FAST" => Some(true),
                "VM_CLASSES_SLOW" | "VM_SUPPORT_SLOW" => Some(false),
                _ => None,
            };
        } else if let (Some(is_fast), Some(name)) = (into, line.strip_prefix('\t')) {
            let file = mdir.join(format!("{}.cpp", name.trim_end_matches('\\').trim()));
            if is_fast { &mut fast } else { &mut slow }.push(file);
        } else {
            into = None;
        }
    }
    let mut listed: Vec<&PathBuf> = fast.iter().chain(&slow).collect();
    listed.sort();
    let mut present: Vec<PathBuf> = std::fs::read_dir(mdir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.starts_with(prefix) && n.ends_with(".cpp") && !n.ends_with("__ALL.cpp")
        })
        .collect();
    present.sort();
    assert!(
        !fast.is_empty() && listed.iter().copied().eq(present.iter()),
        "{}: the class lists {listed:?} are not the model's files {present:?}",
        mk_path.display()
    );
    (fast, slow)
}

/// Verilog, verilated C++, shim and object (steps 1 to 4) of one model, in its own directory.
fn build_model(job: &Job, out: &Path, compiler: &cc::Tool) -> Built {
    let t0 = Instant::now();
    let prefix = &job.prefix;
    let f = prefix.to_lowercase();
    let mdir = out.join(&f);
    let _ = std::fs::remove_dir_all(&mdir);
    std::fs::create_dir_all(&mdir).unwrap();

    // 1. Verilog.
    let t = Instant::now();
    let vfile = out.join(if per_lane(job.design) {
        format!("{}_p{}.v", job.design.name, job.lanes)
    } else {
        format!("{}.v", job.design.name)
    });
    let config = match job.design.params {
        Params::Board(config) => config(),
        Params::Lanes | Params::None => BoardConfig { lanes: job.lanes, ..BoardConfig::default() },
    };
    std::fs::write(&vfile, (job.design.verilog)(&config)).unwrap();
    let t_gen = t.elapsed();

    // 2. Verilate (C++ only: compiled in 4.).
    let t = Instant::now();
    let mut v = Command::new("verilator");
    v.args(["--cc", "--trace", "--timescale", "1ns/1ns", "-O3", "-Wno-fatal", "-Wno-WIDTH", "-Wno-DECLFILENAME"])
        .args(["--prefix", prefix, "--top-module", "top", "--Mdir"])
        .arg(&mdir)
        .arg(&vfile);
    run(&mut v, &format!("verilating {}", vfile.display()));
    let t_verilate = t.elapsed();

    // 3. Shim from the header's port lines.
    let hdr_path = mdir.join(format!("{prefix}.h"));
    let hdr = std::fs::read_to_string(&hdr_path).unwrap();
    let ports = check_ports(parse_ports(&hdr), job.design, &hdr_path);
    let shim = mdir.join(format!("{f}_shim.cpp"));
    let (n_in, n_out) = gen_shim(prefix, &ports, &shim);

    // 4. Compile one unity file, as Verilator's makefile would, but with only the per-clock
    // code (evaluation, trace changes) and the shim optimised: the run-once code
    // (constructors, initial settle, trace declarations and full dump; most of the source)
    // follows a pragma that turns optimisation off. Half the compile time of the makefile's
    // -O2 unity build, the same simulation speed.
    let t = Instant::now();
    let (fast, slow) = class_files(&mdir, prefix);
    let unit = mdir.join(format!("{f}__unity.cpp"));
    let include = |files: &[PathBuf]| -> String {
        files.iter().map(|c| format!("#include \"{}\"\n", c.file_name().unwrap().to_str().unwrap())).collect()
    };
    let text = format!(
        "// Generated by sim/build.rs: do not edit.\n// Per-clock code (VM_*_FAST) and the shim.\n{}{}\
         // Run-once code (VM_*_SLOW), not optimised.\n{UNOPTIMISED}{}",
        include(&fast),
        include(std::slice::from_ref(&shim)),
        include(&slow)
    );
    std::fs::write(&unit, text).unwrap();
    let obj = unit.with_extension("o");
    run(
        compiler
            .to_command()
            .args(["-w", OPT_MODEL, "-I"])
            .arg(&mdir)
            .arg("-I")
            .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("cpp"))
            .arg("-c")
            .arg(&unit)
            .arg("-o")
            .arg(&obj),
        &format!("compiling {}", unit.display()),
    );
    let objects = vec![obj];
    let t_compile = t.elapsed();

    let decls = format!(
        "extern \"C\" {{\n    fn pficp_{f}_new() -> *mut c_void;\n    fn pficp_{f}_free(h: *mut c_void);\n    \
         fn pficp_{f}_tick(h: *mut c_void, t: u64);\n    \
         fn pficp_{f}_trace_open(h: *mut c_void, path: *const c_char, t: u64) -> c_int;\n    \
         fn pficp_{f}_trace_flush(h: *mut c_void);\n    fn pficp_{f}_trace_close(h: *mut c_void);\n    \
         fn pficp_{f}_set_inputs(h: *mut c_void, v: *const u64);\n    \
         fn pficp_{f}_get_outputs(h: *mut c_void, v: *mut u64);\n}}\n"
    );
    // A wide output's name once per u64 word.
    let outputs: Vec<String> = ports
        .iter()
        .filter(|p| !p.input)
        .flat_map(|p| std::iter::repeat_n(format!("{:?}", p.name), p.width.div_ceil(64)))
        .collect();
    let entry = format!(
        "    Model {{ design: \"{}\", lanes: {}, prefix: \"{prefix}\", verilog: \"{}\", in_words: {n_in}, \
         out_words: {n_out}, outputs: &[{}], new: pficp_{f}_new, free: pficp_{f}_free, tick: pficp_{f}_tick, \
         trace_open: pficp_{f}_trace_open, trace_flush: pficp_{f}_trace_flush, trace_close: pficp_{f}_trace_close, \
         set_inputs: pficp_{f}_set_inputs, get_outputs: pficp_{f}_get_outputs }},\n",
        job.design.name,
        job.lanes,
        vfile.display().to_string().escape_default(),
        outputs.join(", ")
    );
    let report = format!(
        "{prefix}: Verilog {} bytes generated in {:.1} s; verilated in {:.1} s; compiled in {:.1} s",
        std::fs::metadata(&vfile).unwrap().len(),
        t_gen.as_secs_f64(),
        t_verilate.as_secs_f64(),
        t_compile.as_secs_f64()
    );
    Built { mdir, objects, decls, entry, report, seconds: t0.elapsed().as_secs_f64() }
}

/// Stack of a build thread (the Verilog generation of the larger designs needs more than the
/// default 2 MiB in an unoptimised build script).
const BUILD_THREAD_STACK: usize = 256 << 20;

/// Build every job on `threads` threads, largest first; results in job order.
fn build_all(jobs: &[Job], threads: usize, out: &Path, compiler: &cc::Tool) -> Vec<Built> {
    // The 16-lane designs take several times as long as the rest: start them first.
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    order.sort_by_key(|&k| std::cmp::Reverse((jobs[k].lanes, jobs[k].design.ports.len())));
    let next = AtomicUsize::new(0);
    let results: Vec<std::sync::Mutex<Option<Built>>> = jobs.iter().map(|_| Default::default()).collect();
    std::thread::scope(|s| {
        for _ in 0..threads.clamp(1, jobs.len()) {
            // rust_hdl builds and walks a design on the stack, and the build script runs
            // unoptimised: the board with the neighbour pipeline's B lanes overflows the
            // default 2 MiB of a spawned thread. The stack is reserved, not committed.
            std::thread::Builder::new()
                .stack_size(BUILD_THREAD_STACK)
                .spawn_scoped(s, || {
                    while let Some(&k) = order.get(next.fetch_add(1, Ordering::Relaxed)) {
                        let built = build_model(&jobs[k], out, compiler);
                        *results[k].lock().unwrap() = Some(built);
                    }
                })
                .expect("spawn a build thread");
        }
    });
    results.into_iter().map(|r| r.into_inner().unwrap().expect("a build thread failed")).collect()
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=cpp/shim.h");
    let t_all = Instant::now();
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let version = verilator_version();
    let include = verilator_include();
    let lanes = lanes_to_build();
    let threads: usize = std::env::var("NUM_JOBS").ok().and_then(|n| n.parse().ok()).unwrap_or(2);
    let mut report = format!("{version}\n");

    let mut b = cc::Build::new();
    b.cpp(true)
        .include(&include)
        .include(include.join("vltstd"))
        .define("VM_COVERAGE", "0")
        .define("VM_SC", "0")
        .define("VM_TRACE", "1")
        .define("VM_TRACE_FST", "0")
        .define("VM_TRACE_VCD", "1")
        .flag("-std=c++17")
        .flag("-faligned-new")
        .flag_if_supported("-Wno-unused-parameter")
        .opt_level(2)
        .debug(false)
        .cargo_warnings(false);
    let compiler = b.get_compiler();

    // 1 to 3: every model, in parallel.
    let jobs: Vec<Job> = DESIGNS
        .iter()
        .flat_map(|d| {
            let ls = if per_lane(d) { lanes.clone() } else { vec![0] };
            ls.into_iter().map(move |p| Job {
                design: d,
                lanes: p,
                prefix: if per_lane(d) { format!("{}{p}", d.prefix) } else { d.prefix.to_string() },
            })
        })
        .collect();
    let t = Instant::now();
    let built = build_all(&jobs, threads, &out, &compiler);
    let mut rs = String::from("// Generated by sim/build.rs: do not edit.\n");
    let mut models = String::new();
    for m in &built {
        writeln!(report, "{} ({:.1} s)", m.report, m.seconds).unwrap();
        rs.push_str(&m.decls);
        models.push_str(&m.entry);
        for o in &m.objects {
            b.object(o);
        }
    }
    writeln!(report, "{} models on {} threads {:.1} s", jobs.len(), threads.min(jobs.len()), t.elapsed().as_secs_f64())
        .unwrap();

    // The runtime (shared by every model), from the smallest model's makefile.
    let t = Instant::now();
    let (k, _) = jobs.iter().enumerate().min_by_key(|(_, j)| (j.lanes, j.design.ports.len())).unwrap();
    let key = fnv1a(&[
        &version,
        OPT_RUNTIME,
        "trace-vcd",
        &std::env::var("CXX").unwrap_or_default(),
        &std::env::var("CXXFLAGS").unwrap_or_default(),
    ]);
    for o in runtime_objects(&built[k].mdir, &jobs[k].prefix, &out, key) {
        b.object(o);
    }
    writeln!(report, "runtime objects {:.1} s (cache key {key:016x})", t.elapsed().as_secs_f64()).unwrap();

    // One archive: shims + models + runtime (no circular dependency between archives).
    let t = Instant::now();
    b.compile("pficp_vpipe");
    println!("cargo:rustc-link-lib=pthread");
    println!("cargo:rustc-link-lib=atomic");
    writeln!(
        report,
        "archive {:.1} s\nbuild.rs total {:.1} s",
        t.elapsed().as_secs_f64(),
        t_all.elapsed().as_secs_f64()
    )
    .unwrap();

    writeln!(rs, "/// The Verilated models.\npub(crate) static MODELS: &[Model] = &[\n{models}];").unwrap();
    writeln!(
        rs,
        "/// Verilator version and build times.\npub const BUILD_REPORT: &str = \"{}\";",
        report.escape_default()
    )
    .unwrap();
    std::fs::write(out.join("models.rs"), rs).unwrap();
    std::fs::write(out.join("build-report.txt"), &report).unwrap();
}
