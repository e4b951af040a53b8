//! Every extreme case of the study (`report::extreme::cases`) on the `cloth` scene
//! either stays finite, is caught by the divergence check with the time and a cause
//! (as given), or is refused with a message naming the field; with safe stepping,
//! none diverges.

use cloth_sandbox::report::extreme::{Outcome, cases, run_case};

#[test]
fn extreme_cases_are_finite_caught_or_refused() {
    for case in cases(true) {
        // The 512x512 cloth is checked separately (its size makes it slow in CI).
        if case.name.starts_with("512") {
            continue;
        }
        let r = run_case(&case, 0.5);
        match &r.raw {
            Outcome::Finite { .. } => {}
            Outcome::Caught { time, message } => {
                assert!(
                    time.is_finite() && message.contains("t = "),
                    "{}: {message}",
                    case.name
                )
            }
            Outcome::Refused(m) => assert!(m.contains('`'), "{}: {m}", case.name),
        }
        assert!(
            !matches!(r.safe, Outcome::Caught { .. }),
            "{} diverged with safe stepping: {:?}",
            case.name,
            r.safe
        );
    }
}

#[test]
fn stiff_light_and_coarse_cases_diverge_as_given_and_are_caught() {
    for name in ["k = 1e6 N/m", "particle mass 1e-6 kg", "dt = 0.1 s"] {
        let case = cases(true).into_iter().find(|c| c.name == name).unwrap();
        let r = run_case(&case, 0.5);
        assert!(
            matches!(r.raw, Outcome::Caught { .. }),
            "{name}: {:?}",
            r.raw
        );
        assert!(
            matches!(r.safe, Outcome::Finite { .. }),
            "{name}: {:?}",
            r.safe
        );
    }
}

#[test]
fn width_zero_is_refused_with_the_field_and_range() {
    let case = cases(true)
        .into_iter()
        .find(|c| c.name == "width 0")
        .unwrap();
    let Outcome::Refused(m) = run_case(&case, 0.5).raw else {
        panic!("width 0 was not refused")
    };
    assert!(m.contains("`width`") && m.contains("[1, 1024]"), "{m}");
}

#[test]
fn degenerate_layouts_stay_finite() {
    for name in [
        "rest length 0 (scene)",
        "rest length scaled to 0 (slider)",
        "every particle pinned (8x8)",
        "none pinned",
        "width 1",
        "height 1",
    ] {
        let case = cases(true).into_iter().find(|c| c.name == name).unwrap();
        let r = run_case(&case, 0.5);
        assert!(
            matches!(r.raw, Outcome::Finite { .. }),
            "{name}: {:?}",
            r.raw
        );
    }
}

#[test]
fn a_512_cloth_takes_a_step() {
    let case = cases(true)
        .into_iter()
        .find(|c| c.name.starts_with("512"))
        .unwrap();
    let mut case = case;
    case.steps = Some(1);
    let r = run_case(&case, 0.5);
    assert!(matches!(r.raw, Outcome::Finite { .. }), "{:?}", r.raw);
}
