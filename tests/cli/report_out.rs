//! `cloth report --out DIR` checks its folder before the study, which takes
//! minutes: a folder that is not empty is refused unless `--force` is given
//! (nothing in it touched), and one that cannot be made or written is refused at
//! once rather than after the whole study.

use std::path::PathBuf;
use std::process::{Command, Output};

fn report(out: &std::path::Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cloth"))
        .args(["report", "--quick", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .expect("runs")
}

fn folder(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("report_out")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_non_empty_folder_is_refused_without_force() {
    let dir = folder("non-empty");
    std::fs::write(dir.join("REPORT.md"), "mine").unwrap();
    std::fs::write(dir.join("notes.txt"), "unrelated").unwrap();
    let o = report(&dir, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("not empty") && err.contains("--force"),
        "{err}"
    );
    assert!(!err.contains("writing"), "refused before the study: {err}");
    assert_eq!(
        std::fs::read_to_string(dir.join("REPORT.md")).unwrap(),
        "mine"
    );
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
}

#[test]
fn a_folder_that_cannot_be_written_is_refused_before_the_study() {
    use std::os::unix::fs::PermissionsExt;
    let dir = folder("read-only");
    let out = dir.join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o555)).unwrap();
    if std::fs::write(out.join("probe"), "").is_ok() {
        // Root writes through permissions: nothing to check here.
        eprintln!("note: skipped, this user can write into a read-only folder");
        return;
    }
    let o = report(&out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("cannot write in the folder"), "{err}");
    assert!(!err.contains(" s] "), "no study before the refusal: {err}");
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o755)).unwrap();
}
