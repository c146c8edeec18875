//! Fuzzing the byte-level board reference (`BoardModel`, docs/protocol.md): random byte
//! streams, truncated frames, frames with flipped bits, overlong frames and well-framed
//! requests with random data. The model never panics; everything it sends is one or more
//! well-formed reply frames; a rejected frame changes nothing; every error code is the one
//! an independent reading of the doc's checks predicts; after garbage and a delimiter, a
//! normal request gets its normal reply.

use pficp_fpga::board::{BoardConfig, BoardModel};
use pficp_fpga::common::format::{unpack_point, FxPoint, WeightScale};
use pficp_fpga::common::splitmix::SplitMix64;
use pficp_fpga::filter::pf::{self, RUN_BYTES};
use pficp_fpga::filter::weights::weights;
use pficp_fpga::protocol::layout::pose_from_bytes;
use pficp_fpga::protocol::messages::{
    parse_two_u16, EvaluateReply, Identity, NearestReply, NearestRequest, ResultReply, RunState, StatusReply,
    FLAG_FIRST, FLAG_LAST,
};
use pficp_fpga::protocol::run_request::{execute, RunOutcome, RunRequest};
use pficp_fpga::protocol::{digest_update, Deframer, ErrorCode, Frame, DIGEST_INIT, MAX_FRAME};
use pficp_fpga::surface::{evaluate_stored, Scored, StoredSearch};
use proptest::prelude::*;

/// SplitMix64: a small deterministic generator (seed from `PFICP_FUZZ_SEED`).
struct Rng(SplitMix64);

impl Rng {
    fn from_env() -> Rng {
        let seed = std::env::var("PFICP_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(0x5eed_b0a2d);
        eprintln!("fuzz seed {seed} (PFICP_FUZZ_SEED)");
        Rng(SplitMix64(seed))
    }
    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }
    fn below(&mut self, n: u64) -> u64 {
        self.0.below(n)
    }
    fn range(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.below(hi - lo + 1)
    }
    fn chance(&mut self, percent: u64) -> bool {
        self.below(100) < percent
    }
    fn byte(&mut self) -> u8 {
        self.next() as u8
    }
    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.byte()).collect()
    }
    fn nonzero(&mut self) -> u8 {
        self.range(1, 255) as u8
    }
    fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[self.below(xs.len() as u64) as usize]
    }
}

/// Stores, sizes, stored costs and the filter's outcome.
#[derive(Clone, PartialEq, Eq)]
struct Snapshot {
    model: Vec<u64>,
    normals: Vec<u64>,
    table: Vec<u16>,
    scan: Vec<u64>,
    sizes: (u16, u16),
    costs: Vec<u64>,
    outcome: Option<RunOutcome>,
    digest: u32,
}

impl Snapshot {
    fn of(b: &BoardModel) -> Snapshot {
        Snapshot {
            model: b.model_store().to_vec(),
            normals: b.normal_store().to_vec(),
            table: b.table_store().to_vec(),
            scan: b.scan_store().to_vec(),
            sizes: b.sizes(),
            costs: b.stored_costs().to_vec(),
            outcome: b.run_outcome().cloned(),
            digest: b.model_digest(),
        }
    }
    fn same_as(&self, b: &BoardModel) -> bool {
        self.sizes == b.sizes()
            && self.costs == b.stored_costs()
            && self.outcome.as_ref() == b.run_outcome()
            && self.model == b.model_store()
            && self.normals == b.normal_store()
            && self.table == b.table_store()
            && self.scan == b.scan_store()
            && self.digest == b.model_digest()
    }

    /// The neighbour pipeline's search and the surface residual over the stores before the
    /// command (any lane count).
    fn search(&self, scan: &[FxPoint], pose: &pficp_fpga::common::format::FxPose) -> Scored {
        evaluate_stored(&self.model, &self.normals, &self.table, scan, pose)
    }
}

/// The frames in bytes the board sent: all of them well-formed replies, nothing left over.
fn replies(out: &[u8]) -> Vec<Frame> {
    if out.is_empty() {
        return Vec::new();
    }
    assert_eq!(*out.last().unwrap(), 0, "output ends inside a frame");
    assert_ne!(out[0], 0, "output starts with a delimiter");
    assert!(!out.windows(2).any(|w| w == [0, 0]), "an empty frame in the output");
    let mut d = Deframer::default();
    let frames: Vec<Frame> =
        out.iter().filter_map(|&b| d.push(b)).map(|r| r.expect("the board sent a malformed frame")).collect();
    assert!(!frames.is_empty());
    for f in &frames {
        assert!(f.code & 0x80 != 0, "a reply without bit 7: {f:?}");
        if f.code == 0xff {
            assert_eq!(f.data.len(), 2, "{f:?}");
            let e = ErrorCode::from_byte(f.data[0]).expect("unknown error code");
            assert_ne!(e, ErrorCode::Busy, "a waiting host never sees Busy");
        } else {
            assert!((0x81..=0x8a).contains(&f.code), "{f:?}");
        }
    }
    frames
}

/// The verdict docs/protocol.md gives for a frame that passed the receiver, written
/// independently of the model: `Ok` or the error code. `ran`: a filter run has finished
/// since power-up (the model never runs one in the background, so never Busy).
fn verdict(sizes: (u16, u16), stored: usize, ran: bool, code: u8, d: &[u8]) -> Result<(), ErrorCode> {
    use ErrorCode::{BadLength, NoResult, OverCapacity, UnknownCommand};
    let field = |at: usize| d[at] as usize + 256 * d[at + 1] as usize;
    let (model, scan) = (sizes.0 as usize, sizes.1 as usize);
    match code {
        0x01 if !d.is_empty() => Err(BadLength),
        0x01 => Ok(()),
        0x02 | 0x03 => {
            if d.len() < 4 || !(1..=170).contains(&field(2)) || d.len() != 4 + 6 * field(2) {
                Err(BadLength)
            } else if field(0) + field(2) > if code == 0x02 { 8192 } else { 4096 } {
                Err(OverCapacity)
            } else {
                Ok(())
            }
        }
        0x0a => {
            if d.len() < 4 || !(1..=510).contains(&field(2)) || d.len() != 4 + 2 * field(2) {
                Err(BadLength)
            } else if field(0) + field(2) > 4097 {
                Err(OverCapacity)
            } else {
                Ok(())
            }
        }
        0x04 if d.len() != 4 => Err(BadLength),
        0x04 if [field(0), field(2)].iter().any(|&s| s == 0 || s > 4096) => Err(OverCapacity),
        0x04 => Ok(()),
        0x05 => {
            if d.len() < 6 {
                return Err(BadLength);
            }
            let n = d[5] as usize;
            let (first, last) = (d[0] & 1 == 1, d[0] & 2 == 2);
            if n > 37 || d.len() != 6 + 27 * n || (n == 0 && !last) {
                return Err(BadLength);
            }
            let after = if first { n } else { stored + n };
            if model == 0 || scan == 0 || after == 0 || after > 256 {
                return Err(OverCapacity);
            }
            Ok(())
        }
        0x06 if d.len() != 31 || field(2) == 0 || field(2) > 144 => Err(BadLength),
        0x06 if model == 0 || scan == 0 || field(0) + field(2) > scan => Err(OverCapacity),
        0x06 => Ok(()),
        // 150 bytes of the filter, 6 of the polish, a pose a start after the first (the
        // sixth byte's low four bits, 0 as 1).
        0x07 if d.len() < 6 || d.len() != 156 + 27 * ((d[5] & 15).max(1) as usize - 1) => Err(BadLength),
        0x07 if field(0) == 0 || field(0) > 256 || field(2) == 0 || model == 0 || scan == 0 => Err(OverCapacity),
        0x07 if field(150) == 0 || field(150) > 4096 => Err(OverCapacity),
        0x07 => Ok(()),
        0x08 | 0x09 if !d.is_empty() => Err(BadLength),
        0x08 => Ok(()),
        0x09 if !ran => Err(NoResult),
        0x09 => Ok(()),
        _ => Err(UnknownCommand),
    }
}

/// Check one executed request's reply against the request and the states before and after.
fn check_reply(request: &Frame, reply: &Frame, before: &Snapshot, b: &BoardModel) {
    assert_eq!(reply.seq, request.seq, "the sequence is echoed");
    let d = &request.data;
    let want = verdict(before.sizes, before.costs.len(), before.outcome.is_some(), request.code, d);
    if reply.code == 0xff {
        assert_eq!(Err(ErrorCode::from_byte(reply.data[0]).unwrap()), want, "request {:#04x} {d:?}", request.code);
        assert_eq!(reply.data[1], request.code);
        assert!(before.same_as(b), "a rejected frame changed the board");
        return;
    }
    assert_eq!(want, Ok(()), "accepted, but the doc rejects: {:#04x} {d:?}", request.code);
    assert_eq!(reply.code, request.code | 0x80);
    let r = &reply.data;
    match request.code {
        0x01 => {
            let (m, s) = b.sizes();
            let c = b.config();
            let id = Identity::of_board(c.lanes as u8, c.clock_hz, c.baud, m, s, b.stored_costs().len() as u16);
            assert_eq!(Identity::decode(r), Ok(id.with_digest(before.digest)));
            assert!(before.same_as(b));
        }
        0x02 | 0x03 => {
            assert_eq!(&r[..], &d[..4]);
            let (offset, count) = parse_two_u16(&d[..4]).unwrap();
            let (offset, count) = (offset as usize, count as usize);
            // LoadModel's words: the points, then their normals; LoadScan's: the scan.
            let (store, old, other, old_other) = if request.code == 0x02 {
                (
                    [b.model_store(), b.normal_store()].concat(),
                    [&before.model[..], &before.normals[..]].concat(),
                    b.scan_store().to_vec(),
                    before.scan.clone(),
                )
            } else {
                (
                    b.scan_store().to_vec(),
                    before.scan.clone(),
                    [b.model_store(), b.normal_store()].concat(),
                    [&before.model[..], &before.normals[..]].concat(),
                )
            };
            for k in 0..store.len() {
                let want = if (offset..offset + count).contains(&k) {
                    let at = 4 + 6 * (k - offset);
                    (0..6).map(|j| (d[at + j] as u64) << (8 * j)).sum()
                } else {
                    old[k]
                };
                assert_eq!(store[k], want, "word {k}");
            }
            assert!(other == old_other);
            assert!(b.table_store() == &before.table[..]);
            // The digest: a LoadModel at offset 0 restarts it, a LoadModel continues it with
            // its data, a LoadScan leaves it.
            let want = match (request.code, offset) {
                (0x02, 0) => digest_update(DIGEST_INIT, d),
                (0x02, _) => digest_update(before.digest, d),
                _ => before.digest,
            };
            assert_eq!(b.model_digest(), want);
            assert_eq!(b.sizes(), before.sizes);
            assert_eq!(b.stored_costs(), &before.costs[..]);
        }
        0x0a => {
            assert_eq!(&r[..], &d[..4]);
            let (offset, count) = parse_two_u16(&d[..4]).unwrap();
            let (offset, count) = (offset as usize, count as usize);
            for k in 0..4097 {
                let want = if (offset..offset + count).contains(&k) {
                    (d[4 + 2 * (k - offset)] as u16 | (d[5 + 2 * (k - offset)] as u16) << 8) & 0x1fff
                } else {
                    before.table[k]
                };
                assert_eq!(b.table_store()[k], want, "entry {k}");
            }
            assert!(
                before.model == b.model_store() && before.normals == b.normal_store() && before.scan == b.scan_store()
            );
            assert_eq!((b.sizes(), b.stored_costs()), (before.sizes, &before.costs[..]));
            assert_eq!(b.model_digest(), digest_update(before.digest, d));
        }
        0x04 => {
            assert_eq!(&r[..], &d[..]);
            assert_eq!(b.sizes(), parse_two_u16(d).unwrap());
            assert_eq!(b.stored_costs(), &before.costs[..]);
        }
        0x05 => {
            let (n, first, last) = (d[5] as usize, d[0] & FLAG_FIRST != 0, d[0] & FLAG_LAST != 0);
            let reply = EvaluateReply::decode(r, n, last).expect("Evaluate reply layout");
            let scan: Vec<FxPoint> = before.scan[..before.sizes.1 as usize].iter().map(|&w| unpack_point(w)).collect();
            let costs: Vec<u64> = d[6..].chunks(27).map(|p| before.search(&scan, &pose_from_bytes(p)).cost).collect();
            assert_eq!(reply.costs, costs);
            let stored = [if first { &[][..] } else { &before.costs[..] }, &costs[..]].concat();
            assert_eq!(b.stored_costs(), &stored[..]);
            if let Some(s) = reply.summary {
                let scale = WeightScale {
                    pre_shift: (d[1] & 63) as u32,
                    q_mul: (d[2] as u32 | (d[3] as u32) << 8 | (d[4] as u32) << 16) & 0x1ffff,
                };
                assert_eq!(s.weights, weights(&stored, &scale));
                assert_eq!(s.min_cost, *stored.iter().min().unwrap());
                assert_eq!(s.w_sum, s.weights.iter().map(|&w| w as u32).sum::<u32>());
            }
            assert_eq!(b.sizes(), before.sizes);
        }
        0x06 => {
            let q = NearestRequest {
                first: parse_two_u16(&d[..4]).unwrap().0,
                count: parse_two_u16(&d[..4]).unwrap().1,
                pose: pose_from_bytes(&d[4..]),
            };
            let reply = NearestReply::decode(r, &q).expect("Nearest reply layout");
            let part: Vec<FxPoint> =
                before.scan[q.first as usize..(q.first + q.count) as usize].iter().map(|&w| unpack_point(w)).collect();
            let e = before.search(&part, &q.pose);
            assert_eq!((reply.cost, reply.results), (e.cost, e.nearest));
            assert!(before.same_as(b));
        }
        0x07 => {
            assert_eq!(&r[..], &d[..4], "particles and iterations echoed");
            let run = RunRequest::decode(d).expect("a Run the doc accepts decodes");
            let points = |n: usize| before.scan[..n].iter().map(|&w| unpack_point(w)).collect::<Vec<FxPoint>>();
            let (scan, polish_scan) = (points(before.sizes.1 as usize), points(run.polish.points as usize));
            let search = StoredSearch { ram: &before.model, normals: &before.normals, first: &before.table };
            let want = execute(&run, |pose| before.search(&scan, pose).evaluated(), &search, &polish_scan);
            assert_eq!(b.run_outcome(), Some(&want));
            assert!(before.sizes == b.sizes() && before.costs == b.stored_costs(), "Run changed the stores");
            assert!(
                before.model == b.model_store() && before.scan == b.scan_store() && before.table == b.table_store()
            );
        }
        0x08 => {
            let s = StatusReply::decode(r).expect("Status reply layout");
            let want = match &before.outcome {
                None => StatusReply { state: RunState::Idle, iterations: 0, best_cost: (1 << 48) - 1 },
                Some(o) => StatusReply {
                    state: RunState::Done,
                    iterations: o.filter.iterations,
                    best_cost: o.filter.best.cost,
                },
            };
            assert_eq!(s, want);
            assert!(before.same_as(b));
        }
        0x09 => {
            let run = before.outcome.as_ref().expect("a result only after a run");
            let o = &run.filter;
            let got = ResultReply::decode(r).expect("Result reply layout");
            assert_eq!(got.polish, run.polish);
            assert_eq!(got.iterations, o.iterations);
            assert_eq!((got.cost, got.max_d2, got.params), (o.best.cost, o.best.max_d2, o.params));
            assert_eq!(got.pose, pf::pose_of(&o.params));
            assert!(before.same_as(b));
        }
        _ => unreachable!(),
    }
}

fn le16(v: u64) -> [u8; 2] {
    [v as u8, (v >> 8) as u8]
}

/// A request with random data, shaped to reach every check of its command (sizes kept
/// small so Evaluate stays cheap).
fn random_request(r: &mut Rng, scan_count: u16) -> Frame {
    let any = r.byte();
    let code = if r.chance(85) { r.range(1, 10) as u8 } else { r.pick(&[0x00, 0x0b, 0x7f, 0x80, 0x85, 0x8a, any]) };
    let seq = r.byte();
    let shape = r.below(100);
    let mut d = match code {
        0x01 => Vec::new(),
        0x02 | 0x03 => {
            let any = r.range(0, 0xffff);
            let count = if r.chance(90) { r.range(1, 170) } else { r.pick(&[0, 171, 0xffff, any]) };
            let offset = match r.below(10) {
                0..=6 => r.range(0, 4096 - count.min(4096)),
                7 => 4096 - count.min(4096) + r.range(0, 3),
                _ => r.range(0, 0xffff),
            };
            let mut d = [le16(offset), le16(count)].concat();
            d.extend(r.bytes(6 * count.min(171) as usize));
            d
        }
        0x0a => {
            // Entries mostly small and increasing (a table), sometimes anything.
            let any = r.range(0, 0xffff);
            let count = if r.chance(90) { r.range(1, 510) } else { r.pick(&[0, 511, 0xffff, any]) };
            let offset = match r.below(10) {
                0..=6 => r.range(0, 4097 - count.min(4097)),
                7 => 4097 - count.min(4097) + r.range(0, 3),
                _ => r.range(0, 0xffff),
            };
            let mut d = [le16(offset), le16(count)].concat();
            let mut at = r.range(0, 64);
            for _ in 0..count.min(511) {
                let e = if r.chance(95) { at } else { r.range(0, 0xffff) };
                d.extend(le16(e));
                at += r.range(0, 2);
            }
            d
        }
        0x04 => {
            let size = |r: &mut Rng, max: u64| match r.below(20) {
                0 => 0,
                1 => 4097,
                2 => r.range(4097, 0xffff),
                3 => 4096,
                _ => r.range(1, max),
            };
            let (m, s) = (size(r, 64), size(r, 48));
            [le16(m), le16(s)].concat()
        }
        0x05 => {
            let any = r.range(0, 37);
            let n = if r.chance(90) { r.range(0, 8) } else { r.pick(&[37, 38, 255, any]) };
            let flags = match r.below(4) {
                0 => r.byte(),
                1 => FLAG_FIRST,
                2 => FLAG_LAST,
                _ => 0,
            };
            let mut d = vec![flags, r.byte(), r.byte(), r.byte(), r.byte(), n as u8];
            d.extend(r.bytes(27 * n.min(37) as usize));
            d
        }
        0x06 => {
            let scan = scan_count.max(1) as u64;
            let count = if r.chance(90) { r.range(1, scan.min(144)) } else { r.pick(&[0, 145, 0xffff, 144]) };
            let first = if r.chance(80) { r.range(0, scan.saturating_sub(count)) } else { r.range(0, 0xffff) };
            let mut d = [le16(first), le16(count)].concat();
            d.extend(r.bytes(27));
            d
        }
        0x07 => {
            // Small runs (the filter runs at once): 1 to 6 particles, 1 to 3 iterations;
            // sometimes out of range.
            let particles = if r.chance(85) { r.range(1, 6) } else { r.pick(&[0, 257, 0xffff, 256]) };
            let iterations = if r.chance(90) { r.range(1, 3) } else { 0 };
            let (particles, iterations) = if particles == 256 { (256, 1) } else { (particles, iterations) };
            let mut d = [le16(particles), le16(iterations)].concat();
            d.extend(r.bytes(RUN_BYTES - 4));
            // The polish: a few points, a few steps (the model runs it at once), sometimes
            // out of range; the starts from the random sixth byte.
            let scan = scan_count.max(1) as u64;
            let points = if r.chance(85) { r.range(1, scan.min(48)) } else { r.pick(&[0, 4097, 0xffff, 4096]) };
            d.extend(le16(points));
            d.push(r.range(0, 2) as u8 | if r.chance(50) { 0xf0 } else { 0 });
            d.extend(r.bytes(3));
            let starts = (d[5] & 15).max(1) as usize;
            d.extend(r.bytes(27 * (starts - 1)));
            d
        }
        0x08 | 0x09 => Vec::new(),
        _ => {
            let n = r.range(0, 40) as usize;
            r.bytes(n)
        }
    };
    // Some lengths off by a little, some random.
    if shape < 8 && !d.is_empty() {
        d.pop();
    } else if shape < 16 {
        d.push(r.byte());
    } else if shape < 20 {
        let n = r.range(0, 60) as usize;
        d = r.bytes(n);
    }
    Frame { code, seq, data: d }
}

/// A request that is accepted, for building garbage from valid frames.
fn valid_request(r: &mut Rng, b: &BoardModel) -> Frame {
    loop {
        let f = random_request(r, b.sizes().1);
        if verdict(b.sizes(), b.stored_costs().len(), b.run_outcome().is_some(), f.code, &f.data).is_ok()
            && f.data.len() < 300
        {
            return f;
        }
    }
}

/// The test's state: the board, its last snapshot and the counts.
struct Fuzz {
    b: BoardModel,
    snap: Snapshot,
    frames_out: usize,
    errors_out: [usize; 8],
    executed: usize,
    overlong_requests: usize,
    /// Accepted Run and Result requests.
    runs: usize,
    results: usize,
}

impl Fuzz {
    fn new() -> Fuzz {
        let b = BoardModel::new(BoardConfig::default());
        let snap = Snapshot::of(&b);
        Fuzz { b, snap, frames_out: 0, errors_out: [0; 8], executed: 0, overlong_requests: 0, runs: 0, results: 0 }
    }

    /// Feed garbage byte by byte: every output is empty (no delimiter) or exactly one
    /// well-formed reply; errors leave the board as it was.
    fn feed(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            let out = self.b.receive(byte);
            if byte != 0 {
                assert!(out.is_empty(), "a reply without a delimiter");
                continue;
            }
            let frames = replies(&out);
            assert!(frames.len() <= 1);
            self.frames_out += frames.len();
            match frames.first() {
                Some(f) if f.code == 0xff => {
                    self.errors_out[f.data[0] as usize] += 1;
                    assert!(self.snap.same_as(&self.b), "an error reply, yet the board changed");
                }
                Some(_) => {
                    // Random bytes that happen to be a valid frame (CRC and all).
                    self.executed += 1;
                    self.snap = Snapshot::of(&self.b);
                }
                None => assert!(self.snap.same_as(&self.b)),
            }
        }
    }

    /// Execute a well-framed request through the wire and check its reply.
    fn request(&mut self, f: &Frame) {
        let wire = f.encode();
        let out = self.b.receive_all(&wire);
        let frames = replies(&out);
        assert_eq!(frames.len(), 1, "one reply per frame");
        if wire.len() - 1 > MAX_FRAME {
            // Too long for the receiver whatever the command.
            assert_eq!(frames[0], Frame::error(0, ErrorCode::BadLength, 0));
            assert!(self.snap.same_as(&self.b));
            self.overlong_requests += 1;
            self.errors_out[ErrorCode::BadLength as usize] += 1;
            return;
        }
        check_reply(f, &frames[0], &self.snap, &self.b);
        self.frames_out += 1;
        if frames[0].code == 0xff {
            self.errors_out[frames[0].data[0] as usize] += 1;
        } else {
            self.executed += 1;
            self.runs += (f.code == 0x07) as usize;
            self.results += (f.code == 0x09) as usize;
            self.snap = Snapshot::of(&self.b);
        }
        // Keep Evaluate cheap: at most 64 model and 48 scan points in use.
        let (m, s) = self.b.sizes();
        if m > 64 || s > 48 {
            let f = Frame { code: 0x04, seq: 1, data: [le16(64), le16(48)].concat() };
            self.request(&f);
        }
    }

    /// A delimiter (the host's resync) and an Identify: its normal reply comes last.
    fn recover(&mut self, seq: u8) {
        let mut out = self.b.receive(0);
        let before = out.len();
        out.extend(self.b.receive_all(&Frame { code: 0x01, seq, data: vec![] }.encode()));
        let frames = replies(&out);
        assert_eq!(frames.len(), 1 + (before > 0) as usize);
        if before > 0 {
            assert_eq!(frames[0].code, 0xff, "a partial frame before the resync");
            self.errors_out[frames[0].data[0] as usize] += 1;
        }
        assert!(self.snap.same_as(&self.b));
        let (m, s) = self.b.sizes();
        let c = self.b.config();
        let id = Identity::of_board(c.lanes as u8, c.clock_hz, c.baud, m, s, self.b.stored_costs().len() as u16);
        let id = id.with_digest(self.b.model_digest());
        assert_eq!(frames.last().unwrap(), &Frame { code: 0x81, seq, data: id.encode() });
    }
}

/// Rounds of the fuzz test in every `cargo test` (each one case and a recovery: about
/// 190,000 reply frames); [`fuzz_the_board_full`] runs 60,000 (over 10^6 frames).
const ROUNDS: u32 = 9000;

#[test]
fn fuzz_the_board() {
    fuzz_rounds(ROUNDS, Rng::from_env());
}

/// Over 10^6 frames through the reference:
/// `cargo test --release -p pficp-fpga --test board_fuzz -- --ignored --nocapture`.
#[test]
#[ignore = "over 10^6 frames: run in release with --ignored"]
fn fuzz_the_board_full() {
    let z = fuzz_rounds(60_000, Rng(SplitMix64(2)));
    assert!(z.frames_out > 1_000_000, "{} reply frames", z.frames_out);
}

/// `rounds` rounds of every kind in turn with `r`; the state at the end.
fn fuzz_rounds(rounds: u32, mut r: Rng) -> Fuzz {
    let start = std::time::Instant::now();
    let mut z = Fuzz::new();
    let mut counts = [0usize; 6];
    // Load something to search, so Evaluate and Nearest get past their capacity checks.
    for code in [0x02, 0x03] {
        let pts: Vec<u8> = (0..170 * 6).map(|k| if k % 2 == 1 { (k % 7) as u8 * 17 } else { r.byte() }).collect();
        z.request(&Frame { code, seq: 0, data: [&le16(0)[..], &le16(170), &pts].concat() });
    }
    // A table that spreads the 170 points over the cells, so rows hold points.
    for at in (0..4097u64).step_by(510) {
        let n = 510.min(4097 - at);
        let entries: Vec<u8> = (at..at + n).flat_map(|k| le16(k * 170 / 4096)).collect();
        z.request(&Frame { code: 0x0a, seq: 0, data: [&le16(at)[..], &le16(n), &entries].concat() });
    }
    z.request(&Frame { code: 0x04, seq: 0, data: [le16(64), le16(48)].concat() });
    for round in 0..rounds {
        let seq = round as u8;
        match round % 6 {
            0 => {
                // Random byte streams: uniform, zero-rich, or long runs without a delimiter.
                let n = r.range(0, 2500) as usize;
                let zeros = r.pick(&[0, 2, 10, 50]);
                let bytes: Vec<u8> =
                    (0..n).map(|_| if zeros > 0 && r.below(zeros) == 0 { 0 } else { r.byte() }).collect();
                z.feed(&bytes);
            }
            1 => {
                // Truncated frames: a valid request cut short, then a delimiter or not.
                let f = valid_request(&mut r, &z.b);
                let w = f.encode();
                let cut = r.range(0, w.len() as u64 - 2) as usize;
                z.feed(&w[..cut]);
                if r.chance(50) {
                    z.feed(&[0]);
                }
            }
            2 => {
                // Flipped bits (a byte flipped to 0 splits the frame in two).
                let f = valid_request(&mut r, &z.b);
                let mut w = f.encode();
                for _ in 0..r.range(1, 3) {
                    let at = r.below(w.len() as u64 - 1) as usize;
                    w[at] ^= 1 << r.below(8);
                }
                z.feed(&w);
            }
            3 => {
                // Overlong: more than MAX_FRAME bytes before the delimiter.
                let junk: Vec<u8> = (0..r.range(MAX_FRAME as u64 + 1, 4000)).map(|_| r.nonzero()).collect();
                let mut w = if r.chance(50) { valid_request(&mut r, &z.b).encode() } else { vec![] };
                w.pop();
                w.extend(junk);
                let out = z.b.receive_all(&w);
                assert!(out.is_empty());
                let out = z.b.receive(0);
                assert_eq!(out, Frame::error(0, ErrorCode::BadLength, 0).encode());
                assert!(z.snap.same_as(&z.b));
                z.errors_out[ErrorCode::BadLength as usize] += 1;
                z.frames_out += 1;
            }
            _ => {
                // Well-framed requests with random data.
                for _ in 0..3 {
                    let f = random_request(&mut r, z.b.sizes().1);
                    z.request(&f);
                }
            }
        }
        counts[(round % 6) as usize] += 1;
        z.recover(seq);
    }
    let took = start.elapsed();
    eprintln!(
        "fuzz: {} random streams, {} truncated, {} bit-flipped, {} overlong, {} requests with random data; \
         {} of them too long for the receiver; {} reply frames ({} executed), errors by code {:?} (BadCrc, BadLength, UnknownCommand, OverCapacity, \
         Busy, BadFrame, NoResult), {:.2} s",
        counts[0],
        counts[1],
        counts[2],
        counts[3],
        3 * (counts[4] + counts[5]),
        z.overlong_requests,
        z.frames_out,
        z.executed,
        &z.errors_out[1..8],
        took.as_secs_f64()
    );
    for code in [1, 2, 3, 4, 6] {
        assert!(z.errors_out[code] > 0, "error code {code} never came up");
    }
    assert!(z.runs > 0 && z.results > 0, "{} runs, {} results", z.runs, z.results);
    assert_eq!(z.errors_out[ErrorCode::Busy as usize], 0);
    z
}

fn loaded_board() -> BoardModel {
    let mut b = BoardModel::new(BoardConfig::default());
    let pts: Vec<u8> = (0..6 * 40).map(|k| (k * 37 % 251) as u8).collect();
    for code in [0x02, 0x03] {
        b.execute(&Frame { code, seq: 0, data: [&le16(0)[..], &le16(40), &pts].concat() });
    }
    let entries: Vec<u8> = (0..510u64).flat_map(|k| le16(k * 40 / 510)).collect();
    b.execute(&Frame { code: 0x0a, seq: 0, data: [&le16(3000)[..], &le16(510), &entries].concat() });
    b.execute(&Frame { code: 0x04, seq: 0, data: [le16(40), le16(30)].concat() });
    assert_eq!(b.sizes(), (40, 30));
    assert_eq!(b.table_store()[3509], 39);
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    /// Any byte stream: only well-formed replies, and a board with only error replies is unchanged.
    #[test]
    fn any_bytes_give_well_formed_replies(bytes in proptest::collection::vec(
        prop_oneof![3 => any::<u8>(), 1 => Just(0u8)], 0..1500)
    ) {
        let mut b = loaded_board();
        let before = Snapshot::of(&b);
        let out = b.receive_all(&bytes);
        let frames = replies(&out);
        prop_assert!(frames.len() <= bytes.iter().filter(|&&x| x == 0).count());
        if frames.iter().all(|f| f.code == 0xff) {
            prop_assert!(before.same_as(&b));
        }
    }

    /// Any well-framed request: the reply the doc's checks predict, echoing the sequence.
    #[test]
    fn any_request_gets_the_predicted_reply(
        code in prop_oneof![4 => 1u8..=6, 1 => Just(0x0au8), 1 => any::<u8>()],
        seq in any::<u8>(),
        head in proptest::collection::vec(any::<u8>(), 0..8),
        n in 0usize..5,
        tail_len in prop_oneof![Just(0usize), Just(27), Just(6), 0usize..40],
        body in proptest::collection::vec(any::<u8>(), 200),
    ) {
        let mut b = loaded_board();
        // Shape the data often enough to pass the length checks.
        let mut data = head.clone();
        match code {
            0x02 | 0x03 if data.len() >= 4 => {
                data.truncate(4);
                data[2] = n as u8;
                data[3] = 0;
                data.extend(&body[..6 * n]);
            }
            0x0a if data.len() >= 4 => {
                data.truncate(4);
                data[2] = 20 * n as u8;
                data[3] = 0;
                data.extend(&body[..40 * n]);
            }
            0x05 if data.len() >= 6 => {
                data.truncate(6);
                data[5] = n as u8;
                data.extend(&body[..27 * n]);
            }
            0x06 if data.len() >= 4 => {
                data.truncate(4);
                data[1] = 0;
                data[3] = 0;
                data.extend(&body[..27]);
            }
            _ => data.extend(&body[..tail_len]),
        }
        let f = Frame { code, seq, data };
        let before = Snapshot::of(&b);
        let out = b.receive_all(&f.encode());
        let frames = replies(&out);
        prop_assert_eq!(frames.len(), 1);
        check_reply(&f, &frames[0], &before, &b);
    }
}
