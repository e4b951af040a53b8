//! Nothing lost in `--dump`: the path is checked before the run (a folder, a device
//! such as `/dev/stdout`, a missing folder, or the scene file itself are refused
//! with exit 2 before any work), the CSV is written atomically, and a diverged
//! run's CSV holds the last finite state and says so.

use std::path::{Path, PathBuf};

use crate::binary::{cloth, stderr};
use std::process::{Command, Output};

/// A fresh folder for one test.
fn folder(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("dump_output")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run_dumping(dump: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "run",
        "--scene",
        "bench",
        "--set",
        "width=4",
        "--set",
        "height=3",
        "--steps",
        "10",
        "--dump",
        dump.to_str().unwrap(),
    ];
    args.extend(extra);
    cloth(&args)
}

#[test]
fn a_folder_is_refused_before_the_run() {
    let dir = folder("folder");
    let o = run_dumping(&dir, &["--json"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("is a folder"), "{}", stderr(&o));
    // Refused before the run: no summary was printed (and lost).
    assert!(o.stdout.is_empty());
}

#[test]
fn a_missing_folder_is_refused_before_the_run() {
    let dir = folder("missing");
    let o = run_dumping(&dir.join("no/such/out.csv"), &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("does not exist"), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
}

#[test]
fn dev_stdout_with_json_is_refused() {
    let o = run_dumping(Path::new("/dev/stdout"), &["--json"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a regular file"), "{}", stderr(&o));
    assert!(o.stdout.is_empty(), "no CSV mixed into the output");
}

#[test]
fn the_scene_file_is_never_overwritten() {
    let dir = folder("scene");
    let scene = dir.join("scene.toml");
    let text = "width = 4\nheight = 3\n";
    std::fs::write(&scene, text).unwrap();
    // Also through another spelling of the same path.
    let other = dir.join(".").join("scene.toml");
    for dump in [&scene, &other] {
        let o = cloth(&[
            "run",
            "--scene",
            scene.to_str().unwrap(),
            "--steps",
            "1",
            "--dump",
            dump.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("scene file"), "{}", stderr(&o));
        assert_eq!(std::fs::read_to_string(&scene).unwrap(), text);
    }
}

#[test]
fn the_dump_replaces_the_file_whole_and_leaves_no_temporary_file() {
    let dir = folder("atomic");
    let csv = dir.join("out.csv");
    std::fs::write(&csv, "old contents\n").unwrap();
    let o = run_dumping(&csv, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("index,x,y,z\n"));
    assert_eq!(text.lines().count(), 13);
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["out.csv"], "only the dump is left");
}

#[test]
fn a_diverged_run_dumps_its_last_finite_state_and_says_so() {
    let dir = folder("diverged");
    let csv = dir.join("out.csv");
    let o = cloth(&[
        "run",
        "--set",
        "dt=1",
        "--steps",
        "50",
        "--json",
        "--dump",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("last state before the divergence"),
        "{}",
        stderr(&o)
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let step = v["diverged"]["step"].as_u64().unwrap();
    assert_eq!(v["diverged"]["dump"]["step"].as_u64(), Some(step - 1));
    let text = std::fs::read_to_string(&csv).unwrap();
    for line in text.lines().skip(1) {
        for field in line.split(',') {
            let x: f64 = field.parse().unwrap();
            assert!(x.is_finite(), "{line}");
        }
    }
    // Still where a cloth can be after one step of 1 s: not thrown kilometres.
    let far = text
        .lines()
        .skip(1)
        .flat_map(|l| l.split(',').skip(1).map(|f| f.parse::<f64>().unwrap()))
        .fold(0.0, |m: f64, x| m.max(x.abs()));
    assert!(
        far < 100.0,
        "the dumped state is the one before the runaway: {far} m"
    );
}

#[test]
fn a_link_to_the_redirected_standard_output_is_refused_and_kept() {
    // `--dump /dev/stdout --json > out.txt`: the link leads to the file the JSON
    // goes to. Here with a link of the test's own, so that nothing outside the
    // test folder is at stake.
    let dir = folder("stdout-link");
    let out = dir.join("out.txt");
    let link = dir.join("stdout");
    let file = std::fs::File::create(&out).unwrap();
    std::os::unix::fs::symlink(&out, &link).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_cloth"))
        .args(["run", "--steps", "1", "--json", "--dump"])
        .arg(&link)
        .stdout(file)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("standard output"), "{}", stderr(&o));
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        "",
        "no CSV in the JSON's file"
    );
}
