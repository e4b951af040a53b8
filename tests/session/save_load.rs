//! Saving the setup (Ctrl+S, the panel's Save) and loading it back, headless: the
//! saved scene file holds the scene, every edited parameter and the pins, and a run
//! loaded from it is bit-identical to the run it was saved from.

use cloth_sandbox::scene::{PinPreset, Pins, Scene};
use cloth_sandbox::session::{Edit, Session};
use cloth_sandbox::sim::Integrator;
use glam::DVec3;

/// A scratch folder of its own under the system temporary directory, emptied first.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("cloth-save-load-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    dir
}

/// Runs `steps` steps of the session's system and returns the positions' bits.
fn run_bits(session: &mut Session, steps: u64) -> Vec<[u64; 3]> {
    session
        .system_mut()
        .run(steps)
        .expect("the run stays stable");
    session
        .system()
        .positions()
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

/// A cloth with a bit of everything the user can change in the panel.
fn edited_cloth() -> Session {
    let mut s = Session::load_with("cloth", &[]).expect("loads");
    for edit in [
        Edit::Stiffness(173.25),
        Edit::Damping(0.0123),
        Edit::ParticleMass(0.0017),
        Edit::RestLength(0.043),
        Edit::Gravity(DVec3::new(0.1, -7.7, 0.0)),
        Edit::Wind(DVec3::new(1.5, 0.0, -2.25)),
        Edit::Gust(0.7),
        Edit::Dt(1.0 / 1500.0),
        Edit::Substeps(11),
        Edit::Width(20),
        Edit::Height(14),
    ] {
        s.apply(edit).unwrap_or_else(|e| panic!("{edit:?}: {e}"));
    }
    s.set_pins(Pins::Preset(PinPreset::TopEdge)).expect("pins");
    s.toggle_pin(5);
    s.toggle_pin(150);
    // The run has moved on since: a save keeps the setup, not the state.
    s.system_mut().run(40).expect("stable");
    s
}

#[test]
fn a_saved_setup_loads_back_to_a_bit_identical_run() {
    let dir = scratch("roundtrip");
    let mut original = edited_cloth();
    let path = original.save_in(&dir).expect("saves");
    assert_eq!(path, dir.join("saved-cloth-1.toml"));
    let pins = original.pins();
    assert!(pins.contains(&150) && !pins.contains(&5), "{pins:?}");

    // As `cloth --scene FILE` and `cloth run --scene FILE` open it.
    let name = path.to_str().expect("a UTF-8 path");
    let mut loaded = Session::load_with(name, &[]).expect("the saved file loads");
    assert_eq!(loaded.settings(), original.settings());
    assert_eq!(loaded.pins(), pins);

    // The unsaved run from its start (a reset rebuilds it from its setup).
    original.reset().expect("resets");
    assert_eq!(run_bits(&mut original, 500), run_bits(&mut loaded, 500));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_builtin_scene_saves_and_loads_back_unchanged() {
    for b in cloth_sandbox::scene::builtin_scenes() {
        let mut original = Session::load_with(b.name, &[]).expect("loads");
        let text = original.scene_text();
        let scene = Scene::parse(&text, "saved text").unwrap_or_else(|e| panic!("{}: {e}", b.name));
        let mut loaded = Session::new(scene, b.name).expect("builds");
        assert_eq!(loaded.settings(), original.settings(), "{}", b.name);
        assert_eq!(
            run_bits(&mut original, 20),
            run_bits(&mut loaded, 20),
            "{}",
            b.name
        );
    }
}

#[test]
fn saving_never_replaces_a_file_and_numbers_the_next() {
    let dir = scratch("numbering");
    let s = Session::load_with("rope", &[]).expect("loads");
    std::fs::write(dir.join("saved-rope-1.toml"), "keep me").expect("writes");
    let second = s.save_in(&dir).expect("saves");
    assert_eq!(second, dir.join("saved-rope-2.toml"));
    assert_eq!(
        std::fs::read_to_string(dir.join("saved-rope-1.toml")).expect("reads"),
        "keep me"
    );
    // A session loaded from a saved file saves under the scene's name again.
    let mut reloaded = Session::load_with(second.to_str().expect("UTF-8"), &[]).expect("loads");
    reloaded
        .apply(Edit::Integrator(Integrator::Rk4))
        .expect("applies");
    assert_eq!(
        reloaded.save_in(&dir).expect("saves"),
        dir.join("saved-rope-3.toml")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn saving_into_a_missing_folder_is_an_error_not_a_panic() {
    let s = Session::load_with("spring", &[]).expect("loads");
    let missing = scratch("missing").join("no/such/folder");
    assert!(s.save_in(&missing).is_err());
}

/// `cloth run --scene FILE --steps N --dump CSV`, returning the CSV.
#[cfg(feature = "app")]
fn cli_dump(dir: &std::path::Path, tag: &str, args: &[&str]) -> String {
    let csv = dir.join(format!("{tag}.csv"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cloth"))
        .arg("run")
        .args(args)
        .args(["--steps", "300", "--dump"])
        .arg(&csv)
        .output()
        .expect("cloth runs");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::read_to_string(&csv).expect("the dump")
}

// Through the binary, which only the `app` feature builds.
#[cfg(feature = "app")]
#[test]
fn cloth_run_reads_a_saved_file_as_the_same_setup_given_by_set() {
    let dir = scratch("cli");
    let mut s = Session::load_with("cloth", &[]).expect("loads");
    s.apply(Edit::Stiffness(173.25)).expect("applies");
    s.apply(Edit::Wind(DVec3::new(1.5, 0.0, -2.25)))
        .expect("applies");
    s.set_pins(Pins::Preset(PinPreset::Corners)).expect("pins");
    s.toggle_pin(77);
    let path = s.save_in(&dir).expect("saves");
    let saved = cli_dump(&dir, "saved", &["--scene", path.to_str().expect("UTF-8")]);
    let given = cli_dump(
        &dir,
        "given",
        &[
            "--scene",
            "cloth",
            "--set",
            "stiffness=173.25",
            "--set",
            "wind=1.5,0,-2.25",
            "--set",
            "pins=[0, 31, 77, 992, 1023]",
        ],
    );
    let unedited = cli_dump(&dir, "unedited", &["--scene", "cloth"]);
    assert_eq!(saved, given);
    assert_ne!(saved, unedited, "the edits change the run");
    let _ = std::fs::remove_dir_all(&dir);
}
