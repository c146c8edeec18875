//! Tracking with the filter on the board: the reference board behind a real
//! pseudo-terminal gives the same tracked frames, to the bit, as the board's bit-exact
//! reference inside the host (the filter's parameters and the held-scale polish's choice),
//! and `pficp track --board` says so in its JSON.

mod support;

use pficp::eval::realistic::Shape;
use pficp::eval::tracking::sequence::sequence;
use pficp::geometry::ScaleBounds;
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::PfIcpSettings;
use pficp::tracking::{TrackSettings, TrackState, Tracker};

#[test]
fn a_track_on_the_board_gives_the_references_poses_to_the_bit() {
    let bunny = pficp::real_shapes::all().iter().find(|s| s.name == "bunny").expect("the bunny");
    let seq = sequence(Shape::Real(bunny), 5, true);
    let nn = NearestNeighbours::new(&seq.model);
    let settings = TrackSettings {
        registration: PfIcpSettings { scale: ScaleBounds::fixed(1.0), seed: 5, ..Default::default() },
        ..Default::default()
    };
    let mut board = support::PtyBoard::reference();
    let mut client = board.client();
    let (mut on_board, uploaded) = Tracker::on_board(&nn, settings.clone(), &mut client).unwrap();
    assert!(uploaded, "a fresh board gets the model");
    let mut reference = Tracker::new(&nn, TrackSettings { board_reference: true, ..settings }).unwrap();
    let mut tracked = 0;
    for (k, f) in seq.frames.iter().take(14).enumerate() {
        let a = on_board.update(&f.scan).unwrap();
        let b = reference.update(&f.scan).unwrap();
        assert_eq!((a.state, a.verdict), (b.state, b.verdict), "frame {k}");
        assert_eq!(a.pose, b.pose, "frame {k}");
        assert_eq!(
            a.board.as_ref().map(|x| (x.pose, x.params, x.polish, x.link_bytes, x.clocks)),
            b.board.as_ref().map(|x| (x.pose, x.params, x.polish, x.link_bytes, x.clocks)),
            "frame {k}"
        );
        if a.state == TrackState::Tracking {
            assert!(a.board.is_some() && !a.global, "frame {k}");
            // The scale is known: the board polishes, holding it.
            let run = &a.board.as_ref().unwrap().run.polish;
            assert!(run.steps > 0 && run.scale == pficp_fpga::polish::ScaleStep::Held, "frame {k}: {run:?}");
            tracked += 1;
        }
    }
    assert!(tracked >= 3, "{tracked} frames tracked on the board");
}
