//! What one command may ask for, so that nothing a user types can start a run
//! that never ends, read a file that never ends, overwrite a file it should not,
//! or echo back a wall of text: the work limits of a run, the size of a scene
//! file, safe output files (checked before the work, written atomically), and
//! the shortening of echoed input.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Most steps one run may take, substeps counted.
pub const MAX_STEPS: u64 = 1_000_000_000;

/// Most particle-steps (steps × particles, substeps counted) one run may take:
/// about a quarter of an hour of the grid kernel on a 1024 × 1024 cloth.
pub const MAX_PARTICLE_STEPS: u64 = 1_000_000_000_000;

/// Largest scene file read, in bytes (the built-in scenes are under 2 KB).
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 20;

/// Longest piece of input echoed back in a message, in characters.
pub const MAX_ECHO_CHARS: usize = 64;

/// Steps for `duration` seconds at `dt`, rounded to the nearest whole step, or
/// an error naming the limit when that is not a finite count of at most
/// [`MAX_STEPS`] steps.
pub fn steps_for_duration(duration: f64, dt: f64) -> Result<u64, String> {
    if !(duration.is_finite() && duration >= 0.0) {
        return Err(format!(
            "--duration {} must be a finite number of seconds >= 0",
            number(duration)
        ));
    }
    let steps = (duration / dt).round();
    if !(steps.is_finite() && steps <= MAX_STEPS as f64) {
        return Err(format!(
            "{} s at dt = {} s is {} steps: a run may take at most {MAX_STEPS} steps; \
             give a shorter duration or a larger dt",
            number(duration),
            number(dt),
            number(steps)
        ));
    }
    Ok(steps as u64)
}

/// What one step costs, counted in particle-steps: every pass of the step, not
/// only the one over the particles. A rope of 100,000 points with 10,000 bar
/// passes a step does 10⁹ bar corrections a step for its 10⁵ particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepWork {
    /// Particles: the force pass and the integration.
    pub particles: usize,
    /// Bar corrections a step: bars times `bar_iterations`.
    pub bar_visits: u64,
    /// Spring visits of the passes after integration: XPBD's and the stretch
    /// limit's, one each over the springs.
    pub spring_visits: u64,
}

/// A bar correction's cost in particle-steps: one bar pass of the 100,000-point
/// rope took 72 ns a bar (`cloth run --scene rope --set width=100000 --set
/// bar_iterations=100 --steps 20`: 14.5 s), a step of the 1024 x 1024 bench
/// cloth 12.6 ns a particle (`--steps 20`: 0.26 s), on the same machine.
pub const BAR_VISIT_COST: f64 = 6.0;

impl StepWork {
    /// The work of a step of `model`.
    pub fn of(model: &crate::sim::Model) -> Self {
        let p = &model.params;
        let springs = model.springs.len() as u64;
        let xpbd = p.integrator == crate::sim::Integrator::Xpbd;
        let passes = u64::from(xpbd) + u64::from(p.stretch_limit.is_some());
        Self {
            particles: model.mass.len(),
            bar_visits: (model.bars.len() as u64).saturating_mul(u64::from(p.bar_iterations)),
            spring_visits: springs.saturating_mul(passes),
        }
    }

    /// A step of `particles` particles and nothing else.
    pub fn particles(particles: usize) -> Self {
        Self {
            particles,
            bar_visits: 0,
            spring_visits: 0,
        }
    }

    /// The step's cost in particle-steps.
    pub fn cost(&self) -> f64 {
        self.particles as f64 + BAR_VISIT_COST * self.bar_visits as f64 + self.spring_visits as f64
    }

    /// What the step holds, for a message: "24 particles" or "100000 particles
    /// and 999990000 bar corrections".
    fn describe(&self) -> String {
        let mut parts = vec![format!("{} particles", self.particles)];
        if self.bar_visits > 0 {
            parts.push(format!(
                "{} bar corrections (bars × bar_iterations, {BAR_VISIT_COST} particle-steps each)",
                self.bar_visits
            ));
        }
        if self.spring_visits > 0 {
            parts.push(format!(
                "{} spring corrections (XPBD, stretch limit)",
                self.spring_visits
            ));
        }
        parts.join(" and ")
    }
}

/// Total steps of a run of `steps` steps of `substeps` substeps each, each step
/// costing `work`, or an error giving the limit when it passes [`MAX_STEPS`]
/// steps or [`MAX_PARTICLE_STEPS`] particle-steps of work (or overflows).
pub fn total_steps(steps: u64, substeps: u64, work: StepWork) -> Result<u64, String> {
    let total = steps.checked_mul(substeps).filter(|&t| t <= MAX_STEPS);
    let Some(total) = total else {
        let shown = (steps as f64) * (substeps as f64);
        return Err(format!(
            "{steps} steps of {substeps} substeps each is {} steps: a run may take at most {MAX_STEPS} steps",
            number(shown)
        ));
    };
    let cost = total as f64 * work.cost();
    if cost.is_nan() || cost > MAX_PARTICLE_STEPS as f64 {
        return Err(format!(
            "{total} steps of {} is {} particle-steps of work: a run may take at most {} \
             particle-steps (steps × particles, each pass counted); give fewer steps, fewer \
             passes or a smaller scene",
            work.describe(),
            number(cost),
            number(MAX_PARTICLE_STEPS as f64)
        ));
    }
    Ok(total)
}

/// A number as a message shows it: plainly when short, else in scientific
/// notation (`1e300`, not three hundred digits), rounded to 5 significant
/// digits when longer.
pub fn number(x: f64) -> String {
    let plain = x.to_string();
    let scientific = format!("{x:e}");
    if plain.len() <= 12 {
        plain
    } else if scientific.len() <= 12 {
        scientific
    } else {
        format!("{x:.4e}")
    }
}

/// A number as the panel shows a setting: four significant digits, in
/// scientific notation only when very large or small.
pub fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let magnitude = x.abs().log10().floor();
    if !(-3.0..6.0).contains(&magnitude) {
        return format!("{x:.3e}");
    }
    let decimals = (3.0 - magnitude).max(0.0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// `text` as a message echoes it: at most [`MAX_ECHO_CHARS`] characters, with
/// the length of what was left out, and with line breaks shown as `\n`.
pub fn echo(text: &str) -> String {
    let escaped: String = text
        .chars()
        .flat_map(|c| {
            let shown: Vec<char> = if c.is_control() {
                c.escape_default().collect()
            } else {
                vec![c]
            };
            shown
        })
        .collect();
    let chars = escaped.chars().count();
    if chars <= MAX_ECHO_CHARS {
        return escaped;
    }
    let head: String = escaped.chars().take(MAX_ECHO_CHARS).collect();
    format!("{head}… ({} more characters)", chars - MAX_ECHO_CHARS)
}

/// Reads a text input file of at most `max_bytes` bytes: anything that is not a
/// regular file (a folder, `/dev/zero`, a pipe) or is larger is refused with a
/// sentence saying why.
pub fn read_text_file(path: &Path, max_bytes: u64) -> Result<String, String> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".to_string());
    }
    if meta.len() > max_bytes {
        return Err(format!(
            "the file is {} bytes, over the limit of {max_bytes} bytes",
            meta.len()
        ));
    }
    let mut text = String::new();
    // Read one byte past the limit, in case the file grew since it was measured.
    File::open(path)
        .and_then(|f| f.take(max_bytes + 1).read_to_string(&mut text))
        .map_err(|e| e.to_string())?;
    if text.len() as u64 > max_bytes {
        return Err(format!("the file is over the limit of {max_bytes} bytes"));
    }
    Ok(text)
}

/// An output file made ready before the work that fills it: the path is checked
/// (not a folder, not a device or pipe, in a folder that exists and can be
/// written) by creating a temporary file next to it, which [`Self::commit`]
/// renames over the target, so that the target is either the old file or the
/// whole new one, never half written. Dropped uncommitted, the temporary file is
/// removed and the target left as it was.
#[derive(Debug)]
pub struct PendingFile {
    target: PathBuf,
    temporary: PathBuf,
    file: Option<File>,
}

impl PendingFile {
    /// Prepares to write `target`; the error says why it cannot be written.
    pub fn create(target: &Path) -> Result<Self, String> {
        let text = target.as_os_str().to_string_lossy();
        if text.ends_with('/') || text.ends_with(std::path::MAIN_SEPARATOR) {
            return Err(match std::fs::metadata(target.components().as_path()) {
                Ok(meta) if !meta.is_dir() => {
                    "ends with / (a folder), but is a file: give a file name".to_string()
                }
                _ => "ends with / (a folder): give a file name".to_string(),
            });
        }
        let mut target = target.to_path_buf();
        if std::fs::symlink_metadata(&target).is_ok() {
            let meta = std::fs::metadata(&target)
                .map_err(|e| format!("cannot be written: {e} (a broken link?)"))?;
            if meta.is_dir() {
                return Err("is a folder: give a file name".to_string());
            }
            if !meta.is_file() {
                return Err(
                    "is not a regular file (a device or a pipe): give a file name".to_string(),
                );
            }
            if is_standard_output(&meta) {
                return Err(
                    "is the standard output or error, where the summary goes: give a file name"
                        .to_string(),
                );
            }
            // Through a link, the file it names is replaced and the link kept.
            target =
                std::fs::canonicalize(&target).map_err(|e| format!("cannot be written: {e}"))?;
        }
        let target = target.as_path();
        let name = target
            .file_name()
            .ok_or_else(|| "has no file name: give a file name".to_string())?;
        let folder = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !folder.is_dir() {
            return Err(if folder.exists() {
                format!("{} is a file, not a folder", folder.display())
            } else {
                format!("the folder {} does not exist", folder.display())
            });
        }
        let mut temporary_name = std::ffi::OsString::from(".");
        temporary_name.push(name);
        temporary_name.push(format!(".{}.tmp", std::process::id()));
        let temporary = folder.join(temporary_name);
        let file = File::create(&temporary)
            .map_err(|e| format!("cannot write in the folder {}: {e}", folder.display()))?;
        Ok(Self {
            target: target.to_path_buf(),
            temporary,
            file: Some(file),
        })
    }

    /// The file being written, to write into.
    pub fn writer(&mut self) -> &mut File {
        self.file.as_mut().expect("open until committed")
    }

    /// Flushes the file and renames it over the target.
    pub fn commit(mut self) -> std::io::Result<()> {
        let mut file = self.file.take().expect("open until committed");
        file.flush()?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&self.temporary, &self.target)
    }
}

impl Drop for PendingFile {
    fn drop(&mut self) {
        // After a commit the temporary file is gone and this does nothing.
        self.file = None;
        let _ = std::fs::remove_file(&self.temporary);
    }
}

/// Whether `meta` is the file this process writes its standard output or error
/// to (`--dump /dev/stdout` with the output redirected to a file).
fn is_standard_output(meta: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ["/dev/stdout", "/dev/stderr"].iter().any(|stream| {
            std::fs::metadata(stream).is_ok_and(|s| s.dev() == meta.dev() && s.ino() == meta.ino())
        })
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        false
    }
}

/// The files a command reads, which none of its outputs may replace, each with
/// what it is ("the scene file", "the scene's mesh"), kept by their canonical
/// paths so that any spelling of an output (`./x`, `../dir/x`, a link to it)
/// meets them.
#[derive(Clone, Debug, Default)]
pub struct Inputs(Vec<(String, PathBuf)>);

impl Inputs {
    /// Adds `path`, read as `what`, if it exists.
    pub fn add(&mut self, what: &str, path: &Path) {
        if let Ok(canonical) = std::fs::canonicalize(path) {
            self.0.push((what.to_string(), canonical));
        }
    }

    /// Refuses `out`, given to `flag`, when it is one of the inputs, however it
    /// is spelled: "--obj scene.toml is the scene file being run: refusing to
    /// overwrite it; give another file name".
    pub fn check(&self, flag: &str, out: &Path) -> Result<(), String> {
        let Some(target) = output_target(out) else {
            return Ok(());
        };
        match self.0.iter().find(|(_, input)| *input == target) {
            Some((what, _)) => Err(format!(
                "{flag} {} is {what}: refusing to overwrite it; give another file name",
                out.display()
            )),
            None => Ok(()),
        }
    }
}

/// The file an output path would write, canonical: through a link at the name to
/// what it names, and the folder canonical when the file does not exist yet
/// (`None` where the folder does not exist either: nothing can be overwritten).
pub fn output_target(out: &Path) -> Option<PathBuf> {
    if let Ok(canonical) = std::fs::canonicalize(out) {
        return Some(canonical);
    }
    let name = out.file_name()?;
    let folder = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    Some(std::fs::canonicalize(folder).ok()?.join(name))
}

/// Whether `a` and `b` name the same existing file (through links or `..`).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// Checks that `out` can take a set of output files before the work that makes
/// them: it is a folder (made if missing) that can be written, and, unless
/// `force`, an empty one, so that no unrelated file is overwritten.
pub fn prepare_output_folder(out: &Path, force: bool) -> Result<(), String> {
    let shown = out.display();
    if out.exists() && !out.is_dir() {
        return Err(format!("{shown} is not a folder"));
    }
    if out.is_dir() && !force {
        let entries = std::fs::read_dir(out)
            .map_err(|e| format!("cannot read the folder {shown}: {e}"))?
            .count();
        if entries > 0 {
            return Err(format!(
                "the folder {shown} is not empty ({entries} entries): give an empty or new folder, \
                 or --force to write into it, replacing files of the same names"
            ));
        }
    }
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create the folder {shown}: {e}"))?;
    let probe = out.join(format!(".cloth-write-test.{}", std::process::id()));
    File::create(&probe).map_err(|e| format!("cannot write in the folder {shown}: {e}"))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}
