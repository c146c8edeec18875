//! The weight stage's RTL against its cycle-accurate reference in rust_hdl's simulator:
//! random stimulus (clear, costs, weigh with random scales, including while busy), every
//! output port compared after every edge.
#![cfg(feature = "rtl")]

use pficp_fpga::common::format::WeightScale;
use pficp_fpga::filter::weights::{WeightInputs, WeightModel, WeightOutputs};
use pficp_fpga::filter::weights_rtl::WeightStage;
use rust_hdl::prelude::*;

fn lcg(seed: &mut u64) -> u64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *seed >> 29
}

/// Per-clock stimulus: mostly costs, then a weigh, some clears, noise on idle buses.
fn stimulus(seed: u64, clocks: usize) -> Vec<WeightInputs> {
    let mut s = seed;
    let base = 5_000_000u64;
    (0..clocks)
        .map(|_| {
            let r = lcg(&mut s) % 100;
            let cost = match lcg(&mut s) % 10 {
                0 => (1 << 48) - 1,
                1 => 0,
                _ => base + lcg(&mut s) % 4_000_000,
            };
            let scale = WeightScale::for_two_q((lcg(&mut s) % 3_000_000 + 1) as f64);
            WeightInputs {
                clear: r < 3,
                cost_valid: (3..60).contains(&r),
                cost,
                weigh: (60..70).contains(&r),
                pre_shift: if r == 69 { 63 } else { scale.pre_shift as u8 },
                q_mul: scale.q_mul,
            }
        })
        .collect()
}

fn set(x: &mut WeightStage, i: &WeightInputs) {
    x.clear.next = i.clear;
    x.cost_valid.next = i.cost_valid;
    x.cost.next = i.cost.into();
    x.weigh.next = i.weigh;
    x.pre_shift.next = (i.pre_shift as u64).into();
    x.q_mul.next = (i.q_mul as u64).into();
}

fn get(x: &WeightStage) -> WeightOutputs {
    WeightOutputs {
        busy: x.busy.val(),
        count: x.count.val().to_u64() as u16,
        min_cost: x.min_cost.val().to_u64(),
        w_valid: x.w_valid.val(),
        w_index: x.w_index.val().to_u64() as u8,
        weight: x.weight.val().to_u64() as u16,
        w_done: x.w_done.val(),
        w_sum: x.w_sum.val().to_u64() as u32,
    }
}

#[test]
fn weight_stage_matches_reference_every_clock() {
    let stim = stimulus(7, 1500);
    let result = std::sync::Arc::new(std::sync::Mutex::new((0u64, 0usize, None::<String>)));
    let out = result.clone();
    let mut uut = WeightStage::new();
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<WeightStage>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<WeightStage>| {
        let mut x = sim.init()?;
        let mut model = WeightModel::new();
        set(&mut x, &WeightInputs::default());
        wait_clock_true!(sim, clock, x);
        model.step(&WeightInputs::default());
        for (clock, i) in stim.iter().enumerate() {
            let (want, got) = (model.outputs(), get(&x));
            if want != got {
                out.lock().unwrap().2 = Some(format!("after edge {clock}: rtl {got:?}\nreference {want:?}"));
                return sim.halt(x);
            }
            let mut o = out.lock().unwrap();
            o.0 = clock as u64 + 1;
            o.1 += want.w_valid as usize;
            drop(o);
            set(&mut x, i);
            wait_clock_cycle!(sim, clock, x);
            model.step(i);
        }
        sim.done(x)
    });
    let run = sim.run(Box::new(uut), 100_000);
    let (clocks, weights, err) = result.lock().unwrap().clone();
    assert!(err.is_none(), "{}", err.unwrap());
    run.expect("simulation");
    assert!(clocks >= 1500, "compared {clocks} clocks");
    assert!(weights > 50, "only {weights} weights came out: the stimulus must exercise the pass");
    eprintln!("weight stage: {clocks} clocks compared, {weights} weights");
}

#[test]
fn weight_stage_verilog_is_valid() {
    let mut uut = WeightStage::new();
    uut.connect_all();
    let v = generate_verilog(&uut);
    yosys_validate("weight_stage", &v).expect("yosys accepts the weight stage");
}
