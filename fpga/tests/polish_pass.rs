//! `PolishPass` with the sequencer's `PipeMul` and `PolishProgram`'s register file, as the
//! board will wire them, in rust_hdl's simulator against
//! [`pficp_fpga::polish::PassSums::add_point`] with [`pficp_fpga::polish::jacobian`]: random
//! found points (images and translations up to the formats' extremes, so the Jacobian
//! saturates now and then; normals of any size; residuals of 13 bits), gated and not, back
//! to back and with gaps; after each pass the 38 registers the pass adds to equal the
//! model's sums.
#![cfg(feature = "rtl")]

use pficp_fpga::format::pack_point;
use pficp_fpga::polish::programs::{solve_inputs, FOUND, INLIERS, SUM_R2};
use pficp_fpga::polish::{jacobian, PassSums};
use pficp_fpga::rtl::board::sequencer::PipeMul;
use pficp_fpga::rtl::polish::{PolishPass, PolishProgram};
use pficp_fpga::splitmix::SplitMix64;
use rust_hdl::prelude::*;
use std::sync::{Arc, Mutex};

/// The pass, the multiplier and the register file wired together.
#[derive(LogicBlock)]
struct PassBench {
    clock: Signal<In, Clock>,
    gated: Signal<In, Bit>,
    tau2: Signal<In, Bits<32>>,
    t: Signal<In, Bits<54>>,
    in_valid: Signal<In, Bit>,
    in_q: Signal<In, Bits<48>>,
    in_n: Signal<In, Bits<48>>,
    in_s: Signal<In, Bits<13>>,
    ready: Signal<Out, Bit>,
    load: Signal<In, Bit>,
    load_addr: Signal<In, Bits<6>>,
    read_addr: Signal<In, Bits<6>>,
    read_data: Signal<Out, Bits<128>>,
    pass: PolishPass,
    mul: PipeMul,
    prog: PolishProgram,
}

impl Logic for PassBench {
    fn update(&mut self) {
        self.pass.clock.next = self.clock.val();
        self.mul.clock.next = self.clock.val();
        self.prog.clock.next = self.clock.val();
        self.pass.reset.next = false;
        self.mul.reset.next = false;
        self.prog.reset.next = false;
        self.pass.gated.next = self.gated.val();
        self.pass.tau2.next = self.tau2.val();
        self.pass.t.next = self.t.val();
        self.pass.in_valid.next = self.in_valid.val();
        self.pass.in_q.next = self.in_q.val();
        self.pass.in_n.next = self.in_n.val();
        self.pass.in_s.next = self.in_s.val();
        self.ready.next = self.pass.ready.val();
        self.mul.go.next = self.pass.mul_go.val();
        self.mul.a.next = self.pass.mul_a.val();
        self.mul.b.next = self.pass.mul_b.val();
        self.pass.mul_product.next = self.mul.product.val();
        self.prog.add.next = self.pass.add.val();
        self.prog.add_addr.next = self.pass.add_addr.val();
        self.prog.add_data.next = self.pass.add_data.val();
        self.prog.load.next = self.load.val();
        self.prog.load_addr.next = self.load_addr.val();
        self.prog.load_data.next = Bits::<128>::default();
        self.prog.read_addr.next = self.read_addr.val();
        self.prog.go.next = false;
        self.prog.entry.next = Bits::<9>::default();
        self.read_data.next = self.prog.read_data.val();
    }

    fn connect(&mut self) {
        self.pass.clock.connect();
        self.mul.clock.connect();
        self.prog.clock.connect();
        self.pass.reset.connect();
        self.mul.reset.connect();
        self.prog.reset.connect();
        self.pass.gated.connect();
        self.pass.tau2.connect();
        self.pass.t.connect();
        self.pass.in_valid.connect();
        self.pass.in_q.connect();
        self.pass.in_n.connect();
        self.pass.in_s.connect();
        self.ready.connect();
        self.mul.go.connect();
        self.mul.a.connect();
        self.mul.b.connect();
        self.pass.mul_product.connect();
        self.prog.add.connect();
        self.prog.add_addr.connect();
        self.prog.add_data.connect();
        self.prog.load.connect();
        self.prog.load_addr.connect();
        self.prog.load_data.connect();
        self.prog.read_addr.connect();
        self.prog.go.connect();
        self.prog.entry.connect();
        self.read_data.connect();
    }
}

/// A 128-bit word as a signed value.
fn value(b: Bits<128>) -> i128 {
    ((b.get_bits::<64>(64).to_u64() as u128) << 64 | b.get_bits::<64>(0).to_u64() as u128) as i128
}

/// One found point: its image, normal and signed residual.
type Point = ([i16; 3], [i16; 3], i64);

/// A pass: the translation, the gate (`None`: statistics only) and its points.
struct Pass {
    t: [i32; 3],
    tau2: Option<u64>,
    points: Vec<Point>,
}

fn passes() -> Vec<Pass> {
    let mut rng = SplitMix64(0x9a55);
    let mut out = Vec::new();
    for case in 0..4 {
        let mut pick = |bits: u32| (rng.next_u64() >> (64 - bits)) as i64 - (1 << (bits - 1));
        // Translations and images near the formats' extremes on the last case: x = q - t
        // reaches 19 bits and the row saturates.
        let wide = case == 3;
        let t: [i32; 3] = std::array::from_fn(|_| if wide { pick(18) as i32 } else { pick(14) as i32 });
        let points: Vec<Point> = (0..24)
            .map(|_| {
                let q = std::array::from_fn(|_| if wide { pick(16) as i16 } else { pick(14) as i16 });
                let n = std::array::from_fn(|_| pick(16) as i16);
                (q, n, pick(if case == 1 { 8 } else { 13 }))
            })
            .collect();
        let tau2 = [None, Some(1 << 12), Some(u64::MAX >> 40), Some(1 << 20)][case];
        out.push(Pass { t, tau2, points });
    }
    out
}

fn model(pass: &Pass) -> PassSums {
    let mut sums = PassSums::new();
    for &(q, n, s) in &pass.points {
        sums.add_point(s, pass.tau2, || jacobian(q, pass.t, n));
    }
    sums
}

#[test]
fn a_pass_adds_the_models_sums() {
    let passes = passes();
    let expected: Vec<[i128; 64]> = passes.iter().map(|p| solve_inputs(&model(p))).collect();
    // The model's gates let some points in and keep some out.
    let sums: Vec<PassSums> = passes.iter().map(model).collect();
    assert!(sums.iter().any(|s| s.inliers > 0 && s.inliers < s.found), "{sums:?}");
    // Some rows saturate, both ways.
    let rows: Vec<[i64; 7]> =
        passes.iter().flat_map(|p| p.points.iter().map(|&(q, n, _)| jacobian(q, p.t, n))).collect();
    assert!(rows.iter().any(|j| j.contains(&((1 << 17) - 1))) && rows.iter().any(|j| j.contains(&-(1 << 17))));
    let found = Arc::new(Mutex::new(Vec::<String>::new()));
    let out = found.clone();
    let mut uut = PassBench {
        clock: Default::default(),
        gated: Default::default(),
        tau2: Default::default(),
        t: Default::default(),
        in_valid: Default::default(),
        in_q: Default::default(),
        in_n: Default::default(),
        in_s: Default::default(),
        ready: Default::default(),
        load: Default::default(),
        load_addr: Default::default(),
        read_addr: Default::default(),
        read_data: Default::default(),
        pass: PolishPass::new(),
        mul: PipeMul::new(),
        prog: PolishProgram::polish(),
    };
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<PassBench>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<PassBench>| {
        let mut x = sim.init()?;
        wait_clock_true!(sim, clock, x);
        for (case, (pass, want)) in passes.iter().zip(&expected).enumerate() {
            for addr in 0..64u64 {
                x.load.next = true;
                x.load_addr.next = addr.into();
                wait_clock_cycle!(sim, clock, x);
            }
            x.load.next = false;
            x.gated.next = pass.tau2.is_some();
            x.tau2.next = Bits::<32>::from(pass.tau2.unwrap_or(0).min(u32::MAX as u64));
            x.t.next = Bits::<54>::from(
                pass.t.iter().enumerate().fold(0u64, |w, (k, &c)| w | ((c as u64) & 0x3_ffff) << (18 * k)),
            );
            for (i, &(q, n, s)) in pass.points.iter().enumerate() {
                while !x.ready.val() {
                    wait_clock_cycle!(sim, clock, x);
                }
                x.in_valid.next = true;
                x.in_q.next = Bits::<48>::from(pack_point(q));
                x.in_n.next = Bits::<48>::from(pack_point(n));
                x.in_s.next = Bits::<13>::from((s as u64) & 0x1fff);
                wait_clock_cycle!(sim, clock, x);
                x.in_valid.next = false;
                // A gap now and then.
                for _ in 0..(i % 3) {
                    wait_clock_cycle!(sim, clock, x);
                }
            }
            // The last point's adds.
            for _ in 0..60 {
                wait_clock_cycle!(sim, clock, x);
            }
            for addr in (0..35).chain([SUM_R2, FOUND, INLIERS].map(|r| r as usize)) {
                x.read_addr.next = (addr as u64).into();
                wait_clock_cycle!(sim, clock, x);
                let got = value(x.read_data.val());
                if got != want[addr] {
                    out.lock().unwrap().push(format!("pass {case}: r{addr} = {got}, the model {}", want[addr]));
                }
            }
        }
        sim.done(x)
    });
    sim.run(Box::new(uut), 1_000_000_000).expect("simulation");
    let errors = found.lock().unwrap();
    assert!(errors.is_empty(), "{} mismatches, the first: {}", errors.len(), errors[0]);
}
