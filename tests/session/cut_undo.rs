//! Cuts are part of the history: Ctrl+Z after a cut puts the springs and the
//! triangles back as they were, so that the run goes on exactly as one never
//! cut; Ctrl+Shift+Z cuts them again; one gesture is one step.

use cloth_sandbox::session::{Edit, Session};

fn cloth() -> Session {
    Session::load_with("cloth", &["width=16".into(), "height=16".into()]).unwrap()
}

fn bits(s: &Session) -> Vec<[u64; 3]> {
    let x = s.system().positions();
    x.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

/// The pairs a cut down the middle of a 16 x 16 grid crosses (columns 7 and 8),
/// rows `rows`.
fn middle(rows: std::ops::Range<usize>) -> Vec<(usize, usize)> {
    rows.flat_map(|r| [(r * 16 + 7, r * 16 + 8), (r * 16 + 7, (r + 1) * 16 + 8)])
        .collect()
}

#[test]
fn undoing_a_cut_mends_it_exactly() {
    let (mut cut, mut whole) = (cloth(), cloth());
    for s in [&mut cut, &mut whole] {
        s.apply(Edit::Stiffness(150.0)).unwrap();
        for _ in 0..5 {
            s.step_frame();
        }
    }
    let springs = whole.system().springs().to_vec();
    let triangles = whole.system().triangles().to_vec();
    // One gesture in two moves, then a second gesture.
    let first = cut.cut(&middle(0..6), false) + cut.cut(&middle(6..10), true);
    let second = cut.cut(&middle(10..15), false);
    assert!(first > 10 && second > 5, "{first} {second}");
    assert_eq!(cut.system().broken_springs(), first + second);
    assert!(cut.system().triangles().len() < triangles.len());

    // Two steps back: the second gesture, then the whole first one.
    assert!(cut.undo().unwrap());
    assert_eq!(cut.system().broken_springs(), first);
    assert!(cut.undo().unwrap());
    assert_eq!(cut.system().broken_springs(), 0);
    assert_eq!(
        cut.system().springs(),
        &springs[..],
        "the springs as they were"
    );
    let mut back = cut.system().triangles().to_vec();
    let mut all = triangles.clone();
    back.sort_unstable();
    all.sort_unstable();
    assert_eq!(back, all, "the triangles as they were");
    // The edit before the cuts is the next step back, not the cut.
    assert!(cut.can_undo());

    // Mended, it runs on exactly as the cloth never cut.
    for _ in 0..30 {
        cut.step_frame();
        whole.step_frame();
    }
    assert_eq!(bits(&cut), bits(&whole));

    // Redo cuts the first gesture again.
    assert!(cut.redo().unwrap());
    assert_eq!(cut.system().broken_springs(), first);
}

#[test]
fn a_cut_mended_after_its_pieces_parted_runs_on() {
    let mut s = Session::load_with("cloth", &[]).unwrap();
    for _ in 0..60 {
        s.step_frame();
    }
    let pairs: Vec<(usize, usize)> = (0..31)
        .flat_map(|c| [(16 * 32 + c, 17 * 32 + c), (16 * 32 + c, 17 * 32 + c + 1)])
        .collect();
    assert!(s.cut(&pairs, false) > 40);
    for _ in 0..90 {
        s.step_frame();
    }
    assert!(s.undo().unwrap());
    for _ in 0..120 {
        s.step_frame();
        assert!(s.divergence().is_none(), "{:?}", s.divergence());
    }
}

/// A cut made in the app (Ctrl + drag across the default cloth, as logged):
/// the time of each move, whether it continues the gesture, and the pairs it crossed.
/// One move: its time (s), whether it continues the gesture, the pairs crossed.
type Move = (f64, bool, &'static [(usize, usize)]);

const CALLS: &[Move] = &[
    (
        7.182456140349817,
        false,
        &[
            (617, 681),
            (618, 682),
            (648, 681),
            (649, 681),
            (649, 682),
            (649, 713),
            (650, 681),
            (650, 682),
            (650, 683),
            (650, 714),
            (651, 682),
        ],
    ),
    (
        7.3105263157883655,
        true,
        &[
            (619, 683),
            (620, 684),
            (651, 683),
            (651, 684),
            (651, 715),
            (652, 683),
            (652, 684),
            (652, 685),
            (652, 716),
        ],
    ),
    (
        7.377192982455007,
        true,
        &[
            (621, 685),
            (622, 686),
            (653, 684),
            (653, 685),
            (653, 686),
            (653, 717),
            (654, 685),
            (654, 686),
            (654, 687),
            (654, 718),
        ],
    ),
    (
        7.5043859649110995,
        true,
        &[
            (623, 687),
            (624, 688),
            (655, 686),
            (655, 687),
            (655, 688),
            (655, 719),
            (656, 687),
            (656, 688),
            (656, 689),
            (656, 720),
            (680, 682),
            (681, 682),
            (681, 683),
            (681, 712),
            (681, 713),
            (681, 714),
            (681, 745),
        ],
    ),
    (
        7.6429824561391175,
        true,
        &[
            (594, 658),
            (625, 658),
            (625, 689),
            (626, 658),
            (626, 690),
            (627, 658),
            (656, 658),
            (657, 658),
            (657, 659),
            (657, 688),
            (657, 689),
            (657, 690),
            (657, 721),
        ],
    ),
    (
        7.77017543859521,
        true,
        &[
            (596, 660),
            (627, 660),
            (627, 691),
            (628, 660),
            (628, 692),
            (629, 660),
            (658, 659),
            (659, 660),
            (659, 661),
            (659, 690),
            (659, 691),
            (659, 692),
            (659, 723),
        ],
    ),
    (
        7.83508771929694,
        true,
        &[
            (598, 662),
            (629, 662),
            (629, 693),
            (630, 662),
            (630, 694),
            (631, 662),
            (660, 661),
            (661, 662),
            (661, 663),
            (661, 692),
            (661, 693),
            (661, 694),
            (661, 725),
        ],
    ),
    (
        7.968421052630223,
        true,
        &[(599, 663), (630, 663), (631, 663), (631, 695), (632, 663)],
    ),
    (
        8.096491228068771,
        true,
        &[
            (597, 661),
            (600, 664),
            (601, 665),
            (628, 661),
            (629, 661),
            (630, 661),
            (631, 664),
            (632, 664),
            (632, 665),
            (632, 696),
            (633, 664),
            (633, 665),
            (633, 697),
        ],
    ),
    (
        8.161403508770501,
        true,
        &[
            (602, 666),
            (633, 666),
            (634, 665),
            (634, 666),
            (634, 667),
            (634, 698),
            (635, 666),
        ],
    ),
];

#[test]
fn a_piece_cut_off_and_fallen_far_comes_back_where_it_was_cut() {
    let mut s = Session::load_with("cloth", &[]).unwrap();
    let run_to = |s: &mut Session, t: f64| {
        while s.system().time() < t {
            s.advance(1.0 / 60.0, 25.0);
            s.settle();
        }
    };
    for (t, continues, pairs) in CALLS {
        run_to(&mut s, *t);
        s.cut(pairs, *continues);
    }
    run_to(&mut s, 11.5);
    // The piece cut off has fallen tens of metres: a spring mended across that
    // gap would hold about 2e6 J.
    let x = s.system().positions();
    let ends = CALLS.iter().flat_map(|c| c.2.iter());
    let gap = ends.map(|&(a, b)| x[a].distance(x[b])).fold(0.0, f64::max);
    assert!(gap > 10.0, "{gap}");
    let cut_at = CALLS[0].0;
    assert!(s.undo().unwrap());
    let back = s.system().time();
    assert!(
        back <= cut_at + 1.0 / 30.0,
        "back to the cloth as it was cut: t = {back}"
    );
    assert!(
        s.system().energy().elastic < 10.0,
        "{:?}",
        s.system().energy()
    );
    for i in 0..120 {
        s.advance(1.0 / 60.0, 25.0);
        s.settle();
        assert!(s.divergence().is_none(), "frame {i}: {:?}", s.divergence());
    }
}
