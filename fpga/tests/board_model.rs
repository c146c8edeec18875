//! The byte-level reference board (`pficp_fpga::board::BoardModel`, docs/protocol.md)
//! command by command: every reply and every error, the stores after each, frames and
//! resynchronisation, and the board against the cycle models of its pipeline and weight
//! stage. The on-board filter's commands (Run, Status, Result) are in `board_run.rs`.

mod support;

use support::*;

use pficp_fpga::search::neighbour_pipeline::{run_particle as grid_run, upload, NeighbourPipelineModel};

#[test]
fn wire_bytes_are_exact() {
    // Computed independently (a separate CRC-16/CCITT-FALSE and COBS in Python) for a
    // 16-lane board at 100 MHz and 921,600 baud, protocol version 7.
    let mut b = BoardModel::new(BoardConfig { lanes: 16, clock_hz: 100_000_000, baud: 921_600 });
    let request = [0x05, 0x01, 0x05, 0x9b, 0x7e, 0x00];
    let reply = [
        0x04, 0x81, 0x05, 0x07, 0x02, 0x10, 0x02, 0x10, 0x02, 0x10, 0x05, 0x01, 0x25, 0xaa, 0x90, 0x04, 0xe1, 0xf5,
        0x05, 0x03, 0x10, 0x0e, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x03, 0x74, 0x4d, 0x00,
    ];
    for (k, &byte) in request.iter().enumerate() {
        let out = b.receive(byte);
        if k + 1 < request.len() {
            assert!(out.is_empty(), "a reply before the delimiter");
        } else {
            assert_eq!(out, reply);
        }
    }
    let sizes = [0x04, 0x04, 0x09, 0x03, 0x02, 0x02, 0x03, 0x73, 0x5d, 0x00];
    assert_eq!(b.receive_all(&sizes), [0x04, 0x84, 0x09, 0x03, 0x02, 0x02, 0x03, 0x53, 0x89, 0x00]);
    assert_eq!(b.sizes(), (3, 2));
    // The same SetSizes with its CRC's low byte flipped: BadCrc, sequence and command 0.
    let mut bad = sizes;
    bad[7] ^= 0x01;
    assert_eq!(b.receive_all(&bad), [0x02, 0xff, 0x02, 0x01, 0x03, 0x52, 0xfc, 0x00]);
}

#[test]
fn identify_reports_config_limits_and_sizes() {
    let config = BoardConfig { lanes: 4, clock_hz: 50_000_000, baud: 115_200 };
    let mut b = BoardModel::new(config);
    assert_eq!(b.config(), config);
    let d = ok(&mut b, req(IDENTIFY, 77, vec![]));
    assert_eq!(d.len(), IDENTITY_BYTES);
    let fields: Vec<u64> = [(0, 2), (2, 1), (3, 2), (5, 2), (7, 2), (9, 1), (10, 1), (11, 1), (12, 4), (16, 4)]
        .iter()
        .map(|&(at, n)| le_at(&d, at, n))
        .collect();
    assert_eq!(
        fields,
        vec![pficp_fpga::protocol::VERSION as u64, 4, 4096, 4096, 256, 37, 170, 144, 50_000_000, 115_200]
    );
    assert_eq!(&d[20..26], &[0; 6], "sizes and stored costs are 0 after power-up");
    ok(&mut b, req(LOAD_MODEL, 1, load_data(0, 1, &[[1, 2, 3]])));
    ok(&mut b, req(SET_SIZES, 2, u16s(1000, 4096)));
    ok(&mut b, req(EVALUATE, 3, eval_data(FLAG_FIRST, 0, 0, 2, &[shift([0; 3]), shift([1, 1, 1])])));
    let d = ok(&mut b, req(IDENTIFY, 4, vec![]));
    assert_eq!(&d[20..26], &[0xe8, 0x03, 0x00, 0x10, 2, 0]);
}

#[test]
fn loads_write_the_stores_and_leave_the_sizes() {
    let mut b = BoardModel::new(BoardConfig::default());
    let pts: Vec<FxPoint> = (0..170)
        .map(|k| [k as i16 * 193 - 16000, -(k as i16) * 7, if k % 2 == 0 { i16::MIN } else { i16::MAX }])
        .collect();
    let d = ok(&mut b, req(LOAD_MODEL, 9, load_data(4096 - 170, 170, &pts)));
    assert_eq!(d, vec![0x56, 0x0f, 0xaa, 0x00], "offset 3926 and count 170 echoed");
    let word = |p: FxPoint| (p[0] as u16 as u64) | (p[1] as u16 as u64) << 16 | (p[2] as u16 as u64) << 32;
    for (k, &p) in pts.iter().enumerate() {
        assert_eq!(b.model_store()[3926 + k], word(p));
        assert_eq!(b.model_store()[3926 + k], pack_point(p));
    }
    assert!(b.model_store()[..3926].iter().all(|&w| w == 0));
    assert!(b.scan_store().iter().all(|&w| w == 0), "LoadModel does not touch the scan");
    let d = ok(&mut b, req(LOAD_SCAN, 10, load_data(5, 2, &[[-1, -1, -1], [1, 0, -2]])));
    assert_eq!(d, u16s(5, 2));
    assert_eq!(b.scan_store()[5..7], [0xffff_ffff_ffff, 0xfffe_0000_0001]);
    assert_eq!(b.scan_store()[4], 0);
    assert_eq!(b.scan_store()[7], 0);
    // Overwriting part of a load.
    ok(&mut b, req(LOAD_SCAN, 11, load_data(6, 1, &[[0, 0, 7]])));
    assert_eq!(b.scan_store()[5..7], [0xffff_ffff_ffff, 7 << 32]);
    assert_eq!(b.sizes(), (0, 0), "loading does not change the sizes");
}

#[test]
fn set_sizes_echoes_its_data() {
    let mut b = BoardModel::new(BoardConfig::default());
    for (m, s) in [(1, 1), (4096, 4096), (4096, 1), (17, 300)] {
        assert_eq!(ok(&mut b, req(SET_SIZES, 0, u16s(m, s))), u16s(m, s));
        assert_eq!(b.sizes(), (m, s));
    }
}

#[test]
fn evaluate_costs_match_the_hand_computation() {
    let mut b = loaded(20);
    let ts = [[0; 3], t_of(1), t_of(2), [-300, 300, 7]];
    let poses: Vec<FxPose> = ts.iter().map(|&t| shift(t)).collect();
    let d = ok(&mut b, req(EVALUATE, 42, eval_data(FLAG_FIRST, 0, 0, 4, &poses)));
    let (costs, summary) = parse_eval(&d, 4, false);
    let want: Vec<u64> = ts.iter().map(|&t| hand_cost(20, t)).collect();
    assert_eq!(costs, want);
    assert!(summary.is_none());
    assert_eq!(b.stored_costs(), &want[..]);
    // Without FIRST the next batch is appended.
    let d = ok(&mut b, req(EVALUATE, 43, eval_data(0, 0, 0, 1, &[shift([5, 5, 5])])));
    assert_eq!(parse_eval(&d, 1, false).0, vec![hand_cost(20, [5, 5, 5])]);
    assert_eq!(b.stored_costs().len(), 5);
    // FIRST forgets them.
    ok(&mut b, req(EVALUATE, 44, eval_data(FLAG_FIRST, 0, 0, 1, &[shift([1, 2, 3])])));
    assert_eq!(b.stored_costs(), &[hand_cost(20, [1, 2, 3])]);
}

#[test]
fn evaluate_and_nearest_match_the_cycle_accurate_pipeline() {
    let mut s = 99u64;
    let mut rnd = |r: i64| {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 33) as i64 % (2 * r + 1) - r) as i16
    };
    // Dense enough that most points find a neighbour within the cap, some not.
    let model: Vec<FxPoint> = (0..1500).map(|_| [rnd(8000), rnd(8000), rnd(8000)]).collect();
    let scan: Vec<FxPoint> = (0..40).map(|_| [rnd(9000), rnd(9000), rnd(9000)]).collect();
    let pose = FxPose::from_f64(&[0.9, -0.3, 0.1, 0.3, 0.9, 0.0, -0.1, 0.05, 0.95], &[0.1, -0.2, 0.05]);
    let mut b = BoardModel::new(BoardConfig::default());
    let g = load_grid(&mut b, &model);
    ok(&mut b, req(LOAD_SCAN, 0, load_data(0, 40, &scan)));
    ok(&mut b, req(SET_SIZES, 0, u16s(1500, 40)));
    let mut pipe = NeighbourPipelineModel::new(b.config().lanes);
    for w in upload(&g) {
        pipe.step(&w);
    }
    let want = grid_run(&mut pipe, &scan, &pose, |_| false).evaluation;
    let capped = want.nearest.iter().filter(|n| n.1 == pficp_fpga::search::grid::CAP_D2).count();
    assert!((1..30).contains(&capped), "{capped} of 40 capped");
    // The costs: the pipeline's results, then each one's surface residual (the test's
    // normals are axes, `test_normal`).
    let resid_cost = |part: &[FxPoint], nearest: &[(u16, u64)]| -> u64 {
        part.iter()
            .zip(nearest)
            .map(|(&p, &(i, d2))| {
                let q = pficp_fpga::common::format::transform(&pose, p);
                pficp_fpga::surface::residual(q, g.points[i as usize], test_normal(i as usize), d2)
            })
            .sum()
    };
    let d = ok(&mut b, req(EVALUATE, 0, eval_data(FLAG_FIRST, 0, 0, 1, &[pose])));
    assert_eq!(parse_eval(&d, 1, false).0, vec![resid_cost(&scan, &want.nearest)]);
    assert_ne!(resid_cost(&scan, &want.nearest), want.cost, "the residual is not the distance");
    let d = ok(&mut b, req(NEAREST, 0, nearest_data(10, 25, &pose)));
    let part = grid_run(&mut pipe, &scan[10..35], &pose, |_| false).evaluation;
    assert_eq!(le_at(&d, 4, 6), resid_cost(&scan[10..35], &part.nearest));
    let got: Vec<(u16, u64)> = (0..25).map(|k| (le_at(&d, 10 + 7 * k, 2) as u16, le_at(&d, 12 + 7 * k, 5))).collect();
    assert_eq!(got, part.nearest);
    assert_eq!(&part.nearest[..], &want.nearest[10..35]);
}

/// The 50 particles of the Evaluate flow: 49 small shifts and one far off (saturated x).
fn fifty() -> Vec<FxPose> {
    (0..50).map(|k| if k == 31 { shift([131_071, 0, 0]) } else { shift(t_of(k)) }).collect()
}

fn fifty_costs(n_scan: usize) -> Vec<u64> {
    let g = grid();
    (0..50)
        .map(|k| {
            if k != 31 {
                return hand_cost(n_scan, t_of(k));
            }
            // x saturates at 32767, far outside the grid: every point costs the cap.
            assert!(g.iter().all(|p| p[0] <= 3000));
            n_scan as u64 * pficp_fpga::search::grid::CAP_D2
        })
        .collect()
}

#[test]
fn fifty_particles_in_two_frames_first_37_then_last_13() {
    let mut b = loaded(20);
    let poses = fifty();
    let want = fifty_costs(20);
    let scale = WeightScale::for_two_q(2.0 * 20.0 * 300.0 * 300.0);
    // Unused flag bits and the high bits of pre_shift and q_mul are ignored.
    let pre = scale.pre_shift as u8 | 0xc0;
    let q = scale.q_mul | 0xfe_0000;
    let d = ok(&mut b, req(EVALUATE, 1, eval_data(FLAG_FIRST | 0xf4, pre ^ 0x3f, !q, 37, &poses[..37])));
    let (costs, summary) = parse_eval(&d, 37, false);
    assert_eq!((costs, summary), (want[..37].to_vec(), None));
    let d = ok(&mut b, req(EVALUATE, 2, eval_data(FLAG_LAST | 0xf8, pre, q, 13, &poses[37..])));
    assert_eq!(d.len(), 13 * 6 + 11 + 50 * 2);
    let (costs, summary) = parse_eval(&d, 13, true);
    assert_eq!(costs, want[37..].to_vec());
    let (stored, min, w_sum, w) = summary.unwrap();
    let (cw, csum, cmin) = weigh_cycles(&want, pre, q);
    assert_eq!((stored, min, w_sum, &w), (50, cmin, csum, &cw));
    assert_eq!(min, *want.iter().min().unwrap());
    assert_eq!(w_sum, w.iter().map(|&x| x as u32).sum::<u32>());
    assert_eq!(w[want.iter().position(|&c| c == min).unwrap()], 65535, "the best particle weighs 1");
    // The far particle's cost is capped (20 x CAP_D2), yet still the largest.
    assert_eq!(w[31], *w.iter().min().unwrap(), "the far particle gets the smallest weight");
    assert!(w.iter().enumerate().all(|(k, &x)| k == 31 || x > w[31]));
    assert!(w.iter().filter(|&&x| x > 1000).count() > 10, "a scale that spreads the weights");
    assert_eq!(b.stored_costs(), &want[..]);
}

#[test]
fn zero_poses_with_last_weighs_the_stored_costs() {
    let mut b = loaded(20);
    let poses = fifty();
    let want = fifty_costs(20);
    ok(&mut b, req(EVALUATE, 1, eval_data(FLAG_FIRST, 0, 0, 37, &poses[..37])));
    ok(&mut b, req(EVALUATE, 2, eval_data(0, 0, 0, 13, &poses[37..])));
    assert_eq!(b.stored_costs(), &want[..]);
    for (pre, q) in [(10u8, 70_000u32), (0, 1), (63, 0x1ffff), (0, 0x1ffff), (5, 0)] {
        let d = ok(&mut b, req(EVALUATE, 3, eval_data(FLAG_LAST, pre, q, 0, &[])));
        let (costs, summary) = parse_eval(&d, 0, true);
        assert!(costs.is_empty());
        let (cw, csum, cmin) = weigh_cycles(&want, pre, q);
        assert_eq!(summary, Some((50, cmin, csum, cw)), "pre_shift {pre} q_mul {q}");
        assert_eq!(b.stored_costs(), &want[..], "weighing keeps the stored costs");
    }
    let id = ok(&mut b, req(IDENTIFY, 4, vec![]));
    assert_eq!(le_at(&id, 24, 2), 50);
    // Full capacity: 256 stored, weighed; the 24-bit sum holds 256 full weights.
    ok(&mut b, req(EVALUATE, 5, eval_data(FLAG_FIRST, 0, 0, 1, &[shift([0; 3])])));
    for _ in 0..255 {
        ok(&mut b, req(EVALUATE, 6, eval_data(0, 0, 0, 1, &[shift([0; 3])])));
    }
    let d = ok(&mut b, req(EVALUATE, 7, eval_data(FLAG_LAST, 0, 1000, 0, &[])));
    let (_, summary) = parse_eval(&d, 0, true);
    let (stored, min, w_sum, w) = summary.unwrap();
    assert_eq!((stored, min, w_sum), (256, hand_cost(20, [0; 3]), 256 * 65535));
    assert!(w.iter().all(|&x| x == 65535));
}

#[test]
fn nearest_returns_indices_distances_and_their_cost() {
    let mut b = loaded(200);
    let t = [-120, 250, 33];
    let d = ok(&mut b, req(NEAREST, 8, nearest_data(50, 144, &shift(t))));
    assert_eq!(d.len(), 10 + 7 * 144);
    assert_eq!((le_at(&d, 0, 2), le_at(&d, 2, 2)), (50, 144));
    let mut cost = 0;
    for k in 0..144 {
        let i = 50 + k;
        assert_eq!(le_at(&d, 10 + 7 * k, 2), home(i) as u64, "point {i}");
        assert_eq!(le_at(&d, 12 + 7 * k, 5), hand_dist(i, t), "point {i}");
        cost += hand_resid(i, t);
    }
    assert_eq!(le_at(&d, 4, 6), cost);
    // The last scan point alone; Nearest leaves the stored costs alone.
    ok(&mut b, req(EVALUATE, 1, eval_data(FLAG_FIRST, 0, 0, 1, &[shift([0; 3])])));
    let before = snap(&b);
    let d = ok(&mut b, req(NEAREST, 9, nearest_data(199, 1, &shift([0; 3]))));
    let dist = hand_dist(199, [0; 3]);
    let resid = hand_resid(199, [0; 3]);
    let mut want = u16s(199, 1);
    want.extend((0..6).map(|k| (resid >> (8 * k)) as u8));
    want.extend([home(199) as u8, 0]);
    want.extend((0..5).map(|k| (dist >> (8 * k)) as u8));
    assert_eq!(d, want);
    assert!(snap(&b) == before);
}

#[test]
fn unknown_commands_are_checked_first() {
    let mut b = loaded(20);
    for code in [0x00, 0x0b, 0x0c, 0x42, 0x7e, 0x7f, 0x80, 0x81, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89, 0xff] {
        for data in [vec![], vec![0; 4], vec![1; 31], vec![0x11; 1029]] {
            rejects(&mut b, req(code, 0x5a, data), ErrorCode::UnknownCommand);
        }
    }
}

#[test]
fn identify_checks() {
    let mut b = BoardModel::new(BoardConfig::default());
    for len in [1, 2, 26, 1000] {
        rejects(&mut b, req(IDENTIFY, 3, vec![0; len]), ErrorCode::BadLength);
    }
}

#[test]
fn load_checks() {
    use ErrorCode::{BadLength, OverCapacity};
    let mut b = loaded(20);
    // LoadScan's words are the scan store's 4,096; LoadModel's 8,192, the model points and
    // then their normals (messages::NORMALS_OFFSET).
    for (code, words) in [(LOAD_MODEL, 8192u16), (LOAD_SCAN, 4096)] {
        let p = [[1, 2, 3]; 171];
        let cases: Vec<(Vec<u8>, ErrorCode)> = vec![
            (vec![], BadLength),
            (vec![0, 0, 1], BadLength),
            (u16s(0, 0), BadLength),
            (load_data(0, 0, &p[..1]), BadLength),
            (load_data(0, 171, &p), BadLength),
            (load_data(4000, 171, &p), BadLength), // lengths before capacities
            (load_data(0, 0xffff, &p[..1]), BadLength),
            (load_data(0, 2, &p[..1]), BadLength),
            (load_data(0, 2, &p[..3]), BadLength),
            ([load_data(0, 2, &p[..2]), vec![0]].concat(), BadLength),
            (load_data(0, 2, &p[..2])[..15].to_vec(), BadLength),
            (load_data(words - 1, 2, &p[..2]), OverCapacity),
            (load_data(words, 1, &p[..1]), OverCapacity),
            (load_data(words - 169, 170, &p[..170]), OverCapacity),
            (load_data(0xffff, 170, &p[..170]), OverCapacity),
        ];
        for (data, e) in cases {
            rejects(&mut b, req(code, 7, data), e);
        }
        ok(&mut b, req(code, 7, load_data(words - 170, 170, &p[..170])));
        ok(&mut b, req(code, 7, load_data(words - 1, 1, &p[..1])));
    }
    // A load across the points' end goes on into the normals.
    ok(&mut b, req(LOAD_MODEL, 8, load_data(4095, 2, &[[4, 5, 6], [7, 8, 9]])));
    assert_eq!(b.model_store()[4095], pficp_fpga::common::format::pack_point([4, 5, 6]));
    assert_eq!(b.normal_store()[0], pficp_fpga::common::format::pack_point([7, 8, 9]));
}

#[test]
fn set_sizes_checks() {
    use ErrorCode::{BadLength, OverCapacity};
    let mut b = loaded(20);
    for (data, e) in [
        (vec![], BadLength),
        (vec![1, 0, 1], BadLength),
        (vec![1, 0, 1, 0, 0], BadLength),
        (vec![0, 0, 0, 0, 0], BadLength), // lengths before capacities
        (u16s(0, 20), OverCapacity),
        (u16s(64, 0), OverCapacity),
        (u16s(0, 0), OverCapacity),
        (u16s(4097, 1), OverCapacity),
        (u16s(1, 4097), OverCapacity),
        (u16s(0xffff, 0xffff), OverCapacity),
    ] {
        rejects(&mut b, req(SET_SIZES, 1, data), e);
    }
}

#[test]
fn evaluate_checks() {
    use ErrorCode::{BadLength, OverCapacity};
    let p = shift([0; 3]);
    let mut fresh = BoardModel::new(BoardConfig::default());
    let mut b = loaded(20);
    for board in [&mut fresh, &mut b] {
        for data in [
            vec![],
            vec![FLAG_FIRST | FLAG_LAST, 0, 0, 0, 0],
            eval_data(FLAG_FIRST, 0, 0, 38, &[p; 38]),
            eval_data(FLAG_FIRST | FLAG_LAST, 0, 0, 255, &[p; 37]),
            eval_data(FLAG_FIRST, 0, 0, 1, &[]),
            eval_data(FLAG_FIRST, 0, 0, 1, &[p; 2]),
            eval_data(FLAG_FIRST, 0, 0, 2, &[p; 1]),
            eval_data(FLAG_FIRST, 0, 0, 1, &[p])[..32].to_vec(),
            [eval_data(FLAG_FIRST, 0, 0, 1, &[p]), vec![0]].concat(),
            eval_data(0, 0, 0, 0, &[]),
            eval_data(FLAG_FIRST, 0, 0, 0, &[]),
            eval_data(FLAG_FIRST | 0xfc, 0, 0, 0, &[]),
            eval_data(0, 0, 0, 0, &[p]),
        ] {
            rejects(board, req(EVALUATE, 4, data), BadLength);
        }
    }
    // Sizes 0 (power-up).
    for flags in [0, FLAG_FIRST, FLAG_LAST, FLAG_FIRST | FLAG_LAST] {
        rejects(&mut fresh, req(EVALUATE, 4, eval_data(flags, 0, 0, 1, &[p])), OverCapacity);
        rejects(&mut fresh, req(EVALUATE, 4, eval_data(flags | FLAG_LAST, 0, 0, 0, &[])), OverCapacity);
    }
    // Nothing to weigh: none stored, or FIRST forgets them all.
    rejects(&mut b, req(EVALUATE, 4, eval_data(FLAG_LAST, 0, 0, 0, &[])), OverCapacity);
    ok(&mut b, req(EVALUATE, 4, eval_data(FLAG_FIRST, 0, 0, 37, &[p; 37])));
    rejects(&mut b, req(EVALUATE, 4, eval_data(FLAG_FIRST | FLAG_LAST, 0, 0, 0, &[])), OverCapacity);
    // More than 256 stored afterwards.
    for _ in 0..5 {
        ok(&mut b, req(EVALUATE, 4, eval_data(0, 0, 0, 37, &[p; 37])));
    }
    ok(&mut b, req(EVALUATE, 4, eval_data(0, 0, 0, 28, &[p; 28])));
    assert_eq!(b.stored_costs().len(), 250);
    rejects(&mut b, req(EVALUATE, 4, eval_data(0, 0, 0, 7, &[p; 7])), OverCapacity);
    rejects(&mut b, req(EVALUATE, 4, eval_data(FLAG_LAST, 0, 0, 37, &[p; 37])), OverCapacity);
    ok(&mut b, req(EVALUATE, 4, eval_data(0, 0, 0, 6, &[p; 6])));
    rejects(&mut b, req(EVALUATE, 4, eval_data(FLAG_LAST, 0, 0, 1, &[p])), OverCapacity);
    ok(&mut b, req(EVALUATE, 4, eval_data(FLAG_LAST, 0, 0, 0, &[])));
    ok(&mut b, req(EVALUATE, 4, eval_data(FLAG_FIRST, 0, 0, 37, &[p; 37])));
    assert_eq!(b.stored_costs().len(), 37);
}

#[test]
fn nearest_checks() {
    use ErrorCode::{BadLength, OverCapacity};
    let p = shift([0; 3]);
    let mut fresh = BoardModel::new(BoardConfig::default());
    let mut b = loaded(20);
    for board in [&mut fresh, &mut b] {
        for data in [
            vec![],
            nearest_data(0, 1, &p)[..30].to_vec(),
            [nearest_data(0, 1, &p), vec![0]].concat(),
            nearest_data(0, 0, &p),
            nearest_data(0, 145, &p),
            nearest_data(0xffff, 0xffff, &p),
        ] {
            rejects(board, req(NEAREST, 5, data), BadLength);
        }
    }
    rejects(&mut fresh, req(NEAREST, 5, nearest_data(0, 1, &p)), OverCapacity);
    for (first, count) in [(15, 6), (20, 1), (0, 21), (0xffff, 1), (0xffff, 144)] {
        rejects(&mut b, req(NEAREST, 5, nearest_data(first, count, &p)), OverCapacity);
    }
    ok(&mut b, req(NEAREST, 5, nearest_data(15, 5, &p)));
    ok(&mut b, req(NEAREST, 5, nearest_data(0, 20, &p)));
}

#[test]
fn frame_errors_are_answered_with_sequence_and_command_0() {
    let mut b = loaded(20);
    let before = snap(&b);
    let err = |e: FrameError| Frame::error(0, e.code(), 0).encode();
    let good = wire(&[SET_SIZES, 9, 1, 0, 1, 0]);
    let mut bad_crc = good.clone();
    bad_crc[good.len() - 2] ^= 0x40;
    let cases: Vec<(Vec<u8>, Vec<u8>)> = vec![
        (vec![0, 0, 0], vec![]),
        ([vec![1; MAX_FRAME + 1], vec![0]].concat(), err(FrameError::BadLength)),
        ([vec![7; 5000], vec![0]].concat(), err(FrameError::BadLength)),
        // 1,034 bytes are taken: code bytes of 1 decode to 1,033 zeros, a CRC mismatch.
        ([vec![1; MAX_FRAME], vec![0]].concat(), err(FrameError::BadCrc)),
        (vec![0x05, 0x01, 0x02, 0x00], err(FrameError::BadFrame)),
        (vec![0xff, 0x00], err(FrameError::BadFrame)),
        (vec![0x01, 0x00], err(FrameError::BadLength)),
        (vec![0x02, 0x05, 0x00], err(FrameError::BadLength)),
        (vec![0x04, 0x01, 0x02, 0x03, 0x00], err(FrameError::BadLength)),
        (bad_crc, err(FrameError::BadCrc)),
        // A flipped command byte: the CRC catches it.
        ([vec![good[0], good[1] ^ 0x01], good[2..].to_vec()].concat(), err(FrameError::BadCrc)),
    ];
    for (bytes, reply) in cases {
        assert_eq!(b.receive_all(&bytes), reply, "{:?}", &bytes[..bytes.len().min(8)]);
        assert!(snap(&b) == before);
        assert_eq!(b.receive_all(&wire(&[IDENTIFY, 3])), identify_reply(&b, 3), "recovers");
    }
    assert_eq!(b.receive_all(&good), Frame { code: 0x84, seq: 9, data: u16s(1, 1) }.encode());
}

#[test]
fn bodies_longer_than_max_body_that_fit_max_frame_reach_the_command_checks() {
    let mut b = loaded(20);
    let before = snap(&b);
    // 1,029 zero data bytes: body 1,031 bytes plus CRC, COBS adds 1 byte: 1,034 on the wire.
    for (code, e) in
        [(0x0b, ErrorCode::UnknownCommand), (LOAD_MODEL, ErrorCode::BadLength), (EVALUATE, ErrorCode::BadLength)]
    {
        let w = wire(&[vec![code, 6], vec![0; 1029]].concat());
        assert_eq!(w.len(), MAX_FRAME + 1);
        assert_eq!(b.receive_all(&w), Frame::error(6, e, code).encode());
        assert!(snap(&b) == before);
    }
}

#[test]
fn every_error_code_but_busy_is_reachable() {
    let mut b = BoardModel::new(BoardConfig::default());
    let mut bad_crc = wire(&[IDENTIFY, 0]);
    let at = bad_crc.len() - 2;
    bad_crc[at] ^= 0x10;
    let streams = [
        bad_crc,
        [vec![1; 2000], vec![0]].concat(),
        wire(&[0x33, 0]),
        wire(&[SET_SIZES, 0, 0, 0, 0, 0]),
        vec![0x09, 0x01, 0x00],
        wire(&[RESULT, 0]),
    ];
    let seen: Vec<u8> = streams
        .iter()
        .map(|s| {
            let out = b.receive_all(s);
            let f = Frame::decode(&out[..out.len() - 1]).unwrap();
            assert_eq!(f.code, 0xff);
            f.data[0]
        })
        .collect();
    // BadCrc, BadLength, UnknownCommand, OverCapacity, BadFrame, NoResult; Busy needs a
    // host that does not wait or a running filter (the RTL tests check it).
    assert_eq!(seen, vec![1, 2, 3, 4, 6, 7]);
    assert_eq!(ErrorCode::Busy as u8, 5);
}

#[test]
fn the_model_digest_follows_model_and_table_loads() {
    use pficp_fpga::protocol::messages::{grid_digest, table_request};
    use pficp_fpga::protocol::{digest_update, DIGEST_INIT, DIGEST_NONE};
    let digest = |b: &mut BoardModel| le_at(&ok(b, req(IDENTIFY, 9, vec![])), 26, 4) as u32;
    let mut b = BoardModel::new(BoardConfig::default());
    assert_eq!(digest(&mut b), DIGEST_NONE, "nothing uploaded since power-up");
    // The host's upload (LoadModel from offset 0, then the table) gives what it predicts.
    let g = load_grid(&mut b, &grid());
    let want = grid_digest(&g, &test_normals(g.points.len()));
    assert_eq!(digest(&mut b), want);
    assert_ne!(want, DIGEST_NONE);
    // Scans, sizes, Evaluate and reset leave it; a rejected load leaves it.
    ok(&mut b, req(LOAD_SCAN, 1, load_data(0, 3, &scan_cloud(3))));
    ok(&mut b, req(SET_SIZES, 2, u16s(64, 3)));
    ok(&mut b, req(EVALUATE, 3, eval_data(FLAG_FIRST, 0, 0, 1, &[shift([0; 3])])));
    b.reset();
    rejects(&mut b, req(LOAD_MODEL, 4, load_data(8191, 2, &grid()[..2])), ErrorCode::OverCapacity);
    assert_eq!(digest(&mut b), want);
    // Any table or model write changes it; the same bytes again continue it.
    let t = table_request(5, &[1, 2]);
    ok(&mut b, req(LOAD_TABLE, 5, t.clone()));
    assert_eq!(digest(&mut b), digest_update(want, &t));
    let m = load_data(7, 1, &[[1, 2, 3]]);
    ok(&mut b, req(LOAD_MODEL, 6, m.clone()));
    assert_eq!(digest(&mut b), digest_update(digest_update(want, &t), &m));
    // A LoadModel at offset 0 restarts it: uploading the grid again gives the same digest.
    load_grid(&mut b, &grid());
    assert_eq!(digest(&mut b), want);
    let m0 = load_data(0, 1, &[[1, 2, 3]]);
    ok(&mut b, req(LOAD_MODEL, 7, m0.clone()));
    assert_eq!(digest(&mut b), digest_update(DIGEST_INIT, &m0));
}
