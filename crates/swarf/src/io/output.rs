//! Outputs: the files of one run written together, never over an input.
//!
//! [`commit`] first refuses, before anything is written, an output that is the same file as
//! one of the run's inputs (compared by identity, device and inode through `same-file`, so a
//! hard link, a symbolic link or `./case/../case.json` is caught as well as the same name), an
//! output that exists and is not a regular file (a device such as `/dev/null`, a folder, a
//! pipe), and two outputs that are the same file. It then writes each file to a temporary file
//! beside its target (created new, never opened over something that is there) and renames the
//! temporaries into place only once all are written: a failure leaves the old outputs as they
//! were and no temporary behind.
//!
//! A program that stops on a signal calls [`interrupt`] from its handler: it waits for a
//! renaming in progress to finish (so the outputs are all new or all old), removes every
//! temporary still in flight, and makes any later [`commit`] fail. Only a kill that cannot be
//! handled (SIGKILL, a power cut) can leave a temporary file (`.NAME.swarf-tmp-PID`) behind.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The temporary files written and not yet renamed, of every commit in progress.
struct InFlight {
    temps: Vec<PathBuf>,
    interrupted: bool,
}

static IN_FLIGHT: Mutex<InFlight> = Mutex::new(InFlight { temps: Vec::new(), interrupted: false });

fn in_flight() -> std::sync::MutexGuard<'static, InFlight> {
    // (a panic while the lock was held leaves a list that is still right)
    IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner())
}

/// One output file and its contents.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputFile {
    /// Where it goes.
    pub path: PathBuf,
    /// What it holds.
    pub bytes: Vec<u8>,
}

impl OutputFile {
    /// `bytes` to be written to `path`.
    pub fn new(path: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) -> Self {
        OutputFile { path: path.into(), bytes: bytes.into() }
    }
}

/// The place a path names, for comparing outputs that do not exist yet: its folder resolved
/// (links and `..` followed) and its file name; the path made absolute where the folder does
/// not exist.
fn place_of(path: &Path) -> PathBuf {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) => dir.canonicalize().map_or_else(|_| abs.clone(), |d| d.join(name)),
        _ => abs,
    }
}

/// Refuses `outputs` that would replace one of `inputs`, that exist and are not regular files,
/// or that name one file twice; writes nothing.
pub fn check(outputs: &[&Path], inputs: &[&Path]) -> Result<()> {
    let refused = |p: &Path, reason: String| Err(Error::Refused { file: p.to_path_buf(), reason });
    for (i, &out) in outputs.iter().enumerate() {
        if let Ok(meta) = std::fs::metadata(out)
            && !meta.is_file()
        {
            let what = if meta.is_dir() { "a folder" } else { "not a regular file (a device, pipe or socket)" };
            return refused(out, format!("the output is {what}: swarf writes outputs to regular files only"));
        }
        for &input in inputs {
            if same_file::is_same_file(out, input).unwrap_or(false) {
                return refused(
                    out,
                    format!("the output is the input {}: an output never replaces an input", input.display()),
                );
            }
        }
        for &other in &outputs[..i] {
            if same_file::is_same_file(out, other).unwrap_or(false) || place_of(out) == place_of(other) {
                return refused(out, "two outputs are this one file: give each output its own name".into());
            }
        }
    }
    Ok(())
}

/// A temporary file beside `path` that does not exist yet, created, and listed as in flight.
fn create_temp(path: &Path) -> Result<(PathBuf, std::fs::File)> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    let mut flight = in_flight();
    if flight.interrupted {
        return Err(Error::Output { what: path.display().to_string(), reason: "interrupted: nothing written".into() });
    }
    for k in 0u32.. {
        let tmp = match k {
            0 => dir.join(format!(".{name}.swarf-tmp-{}", std::process::id())),
            _ => dir.join(format!(".{name}.swarf-tmp-{}-{k}", std::process::id())),
        };
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => {
                flight.temps.push(tmp.clone());
                return Ok((tmp, f));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && k < 100 => continue,
            Err(source) => return Err(Error::Io { path: path.to_path_buf(), source }),
        }
    }
    unreachable!("the loop returns by k = 100")
}

/// Removes `temps` from the disk and from the list in flight.
fn discard(temps: &[PathBuf]) {
    let mut flight = in_flight();
    for t in temps {
        let _ = std::fs::remove_file(t);
    }
    flight.temps.retain(|t| !temps.contains(t));
}

/// Writes `files` together after [`check`]ing them against `inputs`: every file is written to a
/// temporary beside it, and the temporaries are renamed into place only once all are written.
/// On an error nothing is replaced and no temporary is left.
///
/// ```
/// use swarf::io::output::{OutputFile, commit};
/// let dir = std::env::temp_dir().join(format!("swarf-commit-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let case = dir.join("case.json");
/// std::fs::write(&case, "{}")?;
/// // the input is refused as an output, and nothing is written
/// let both = [OutputFile::new(dir.join("a.ngc"), "G0\n"), OutputFile::new(&case, "G0\n")];
/// assert!(commit(&both, &[case.as_path()]).is_err());
/// assert!(!dir.join("a.ngc").exists() && std::fs::read_to_string(&case)? == "{}");
/// commit(&both[..1], &[case.as_path()])?;
/// assert_eq!(std::fs::read_to_string(dir.join("a.ngc"))?, "G0\n");
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn commit(files: &[OutputFile], inputs: &[&Path]) -> Result<()> {
    let outputs: Vec<&Path> = files.iter().map(|f| f.path.as_path()).collect();
    check(&outputs, inputs)?;
    let mut temps: Vec<PathBuf> = Vec::with_capacity(files.len());
    for f in files {
        let written = create_temp(&f.path).and_then(|(tmp, mut file)| {
            temps.push(tmp);
            file.write_all(&f.bytes)
                .and_then(|()| file.sync_all())
                .map_err(|source| Error::Io { path: f.path.clone(), source })
        });
        if let Err(e) = written {
            discard(&temps);
            return Err(e);
        }
    }
    // (the list held through the renaming: a signal's interrupt() waits for all of them)
    let mut flight = in_flight();
    if flight.interrupted {
        drop(flight);
        discard(&temps);
        return Err(Error::Output { what: "outputs".into(), reason: "interrupted: nothing written".into() });
    }
    for (i, (f, tmp)) in files.iter().zip(&temps).enumerate() {
        if let Err(source) = std::fs::rename(tmp, &f.path) {
            for t in &temps[i..] {
                let _ = std::fs::remove_file(t);
            }
            flight.temps.retain(|t| !temps.contains(t));
            return Err(Error::Io { path: f.path.clone(), source });
        }
    }
    flight.temps.retain(|t| !temps.contains(t));
    Ok(())
}

/// For a signal handler: waits for a renaming in progress, removes every temporary file in
/// flight, and makes later [`commit`]s fail. The handler then ends the program.
pub fn interrupt() {
    let mut flight = in_flight();
    flight.interrupted = true;
    for t in flight.temps.drain(..) {
        let _ = std::fs::remove_file(t);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("swarf-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn listing(d: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn an_output_that_is_an_input_by_another_name_is_refused_and_nothing_is_written() {
        let d = scratch("same");
        let input = d.join("case.json");
        std::fs::write(&input, "{}").unwrap();
        std::fs::create_dir(d.join("sub")).unwrap();
        let hard = d.join("hard.json");
        std::fs::hard_link(&input, &hard).unwrap();
        for alias in [input.clone(), d.join("sub/../case.json"), hard] {
            let files = [OutputFile::new(d.join("out.ngc"), "x"), OutputFile::new(&alias, "y")];
            let e = commit(&files, &[input.as_path()]).unwrap_err();
            assert!(matches!(e, Error::Refused { .. }), "{alias:?}: {e}");
            assert!(e.to_string().contains("never replaces an input"), "{e}");
        }
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "{}");
        assert_eq!(listing(&d), ["case.json", "hard.json", "sub"]);
    }

    #[test]
    fn devices_folders_and_one_file_named_twice_are_refused() {
        let d = scratch("kinds");
        for (out, why) in [(PathBuf::from("/dev/null"), "regular files"), (d.clone(), "a folder")] {
            let e = commit(&[OutputFile::new(&out, "x")], &[]).unwrap_err();
            assert!(e.to_string().contains(why), "{e}");
        }
        let twice = [OutputFile::new(d.join("a.ngc"), "x"), OutputFile::new(d.join("./a.ngc"), "y")];
        assert!(commit(&twice, &[]).unwrap_err().to_string().contains("two outputs"));
        assert!(listing(&d).is_empty());
    }

    #[test]
    fn outputs_replace_old_ones_together_and_leave_no_temporary() {
        let d = scratch("commit");
        std::fs::write(d.join("a.ngc"), "old").unwrap();
        commit(&[OutputFile::new(d.join("a.ngc"), "new a"), OutputFile::new(d.join("b.json"), "new b")], &[]).unwrap();
        assert_eq!(std::fs::read_to_string(d.join("a.ngc")).unwrap(), "new a");
        assert_eq!(listing(&d), ["a.ngc", "b.json"]);
        // a second file that cannot be written (its folder is missing): the first stays old
        let e = commit(&[OutputFile::new(d.join("a.ngc"), "newer"), OutputFile::new(d.join("no/b"), "b")], &[]);
        assert!(matches!(e, Err(Error::Io { .. })));
        assert_eq!(std::fs::read_to_string(d.join("a.ngc")).unwrap(), "new a");
        assert_eq!(listing(&d), ["a.ngc", "b.json"]);
    }
}
