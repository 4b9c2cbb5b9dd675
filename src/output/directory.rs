//! [`OutputDirectory`]: the one way commands write a directory of results.
//!
//! A run writes into a fresh *staging* directory beside the target
//! (`.NAME.partial-PID` in the same parent, so that a rename moves it) and
//! [`OutputDirectory::commit`] renames it into place at the end: readers
//! see the old results or the new ones, never a mixture, and a run that
//! fails (or is killed) leaves the old results as they were. A target that
//! is not empty is refused unless the caller allows replacing it, and then
//! it is replaced whole. A lock file beside the target (`.NAME.lock`,
//! created exclusively, holding the owner's process id) keeps two runs from
//! sharing one target; a lock whose process no longer exists (a killed run)
//! is taken over, and so is an empty or unreadable lock file older than
//! [`UNREADABLE_LOCK_SECONDS`]. What a killed run left beside the target
//! is cleaned up by the next run, under the lock: its staging directory is
//! removed, and old results it had moved aside (`.NAME.old-PID`, between
//! the two renames of a commit) are put back if the target is missing.
//! A process that must stop at once (the command line's second Ctrl-C)
//! calls [`abandon_uncommitted`]: it removes every staging directory and
//! lock of this process and keeps any later commit from starting, so that
//! each target is either committed whole or untouched, with nothing left
//! beside it. Every error names the path it concerns.

use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use thiserror::Error;

/// Why an output directory or file could not be written.
#[derive(Debug, Error)]
pub enum OutputError {
    /// An I/O operation on `path` failed.
    #[error("{action} {path}: {error}")]
    Io {
        /// What was being done (`creating`, `writing`, ...).
        action: &'static str,
        /// The path it was done to.
        path: PathBuf,
        /// The operating system's error, shown in the message (not as a
        /// separate cause, which would print it twice).
        error: std::io::Error,
    },
    /// A plot could not be drawn or written.
    #[error("drawing {path}: {problem}")]
    Plot {
        /// The plot's file.
        path: PathBuf,
        /// What went wrong.
        problem: String,
    },
    /// The target exists and holds files, and replacing it was not allowed.
    #[error(
        "refusing to write into {path}: it is not empty (results of an earlier run?); \
         choose another directory or give --force to replace it whole"
    )]
    NotEmpty {
        /// The target directory.
        path: PathBuf,
    },
    /// The target exists and is not a directory.
    #[error("{path} exists and is not a directory")]
    NotADirectory {
        /// The target.
        path: PathBuf,
    },
    /// Another run holds the target's lock.
    #[error(
        "{path} is being written by another run (process {owner} holds the lock file {lock}); \
         wait for it to finish, or delete the lock file if no such run exists"
    )]
    Locked {
        /// The target directory.
        path: PathBuf,
        /// The lock file.
        lock: PathBuf,
        /// The process id recorded in the lock file.
        owner: String,
    },
}

impl OutputError {
    /// An I/O error of `action` on `path`.
    pub fn io(action: &'static str, path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            action,
            path: path.to_path_buf(),
            error: source,
        }
    }
}

/// The staging directories and locks of this process's uncommitted
/// [`OutputDirectory`]s. A commit holds it while it renames, so that
/// [`abandon_uncommitted`] sees each directory either before or after.
static UNCOMMITTED: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());

/// [`UNCOMMITTED`], held (a panic elsewhere does not stop the clean-up).
fn uncommitted() -> MutexGuard<'static, Vec<(PathBuf, PathBuf)>> {
    UNCOMMITTED.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Held while the process stops: no [`OutputDirectory::commit`] starts.
pub struct Abandoned {
    _held: MutexGuard<'static, Vec<(PathBuf, PathBuf)>>,
}

/// Removes the staging directory and the lock of every uncommitted
/// [`OutputDirectory`] of this process, leaving their targets as they
/// were, and blocks every commit while the returned guard is held: hold
/// it until the process exits. A commit under way finishes first (its
/// target is then complete).
pub fn abandon_uncommitted() -> Abandoned {
    let mut open = uncommitted();
    for (staging, lock) in open.drain(..) {
        let _ = fs::remove_dir_all(&staging);
        let _ = fs::remove_file(&lock);
    }
    Abandoned { _held: open }
}

/// Writes `contents` to `path`, naming the path in any error.
pub fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> Result<(), OutputError> {
    fs::write(path, contents).map_err(|e| OutputError::io("writing", path, e))
}

/// Creates the directory `path` and its parents, naming the path in any error.
pub fn create_dir(path: &Path) -> Result<(), OutputError> {
    fs::create_dir_all(path).map_err(|e| OutputError::io("creating", path, e))
}

/// A directory of results being written: files go into [`Self::path`], a
/// staging directory, until [`Self::commit`] renames it to the target
/// (module documentation). Dropped without a commit, it removes the
/// staging directory and leaves the target untouched.
#[derive(Debug)]
pub struct OutputDirectory {
    target: PathBuf,
    staging: PathBuf,
    /// Where an old target is moved during [`Self::commit`].
    old: PathBuf,
    lock: PathBuf,
    replace: bool,
    committed: bool,
}

impl OutputDirectory {
    /// Takes the lock of `target` and creates an empty staging directory.
    /// A `target` that exists and is not empty is an error unless `replace`
    /// (then [`Self::commit`] replaces it whole); one that is not a
    /// directory is always an error.
    pub fn create(target: &Path, replace: bool) -> Result<Self, OutputError> {
        let name = target
            .file_name()
            .ok_or_else(|| OutputError::NotADirectory {
                path: target.to_path_buf(),
            })?
            .to_string_lossy()
            .into_owned();
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        create_dir(&parent)?;
        check_target(target, replace)?;
        let lock = parent.join(format!(".{name}.lock"));
        let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
        let old = parent.join(format!(".{name}.old-{}", std::process::id()));
        // The lock is registered as soon as it is taken, so that an
        // abandon removes it, and an error from here on drops `directory`,
        // which removes it too.
        let mut open = uncommitted();
        take_lock(target, &lock)?;
        open.push((staging.clone(), lock.clone()));
        drop(open);
        let directory = Self {
            target: target.to_path_buf(),
            staging,
            old,
            lock,
            replace,
            committed: false,
        };
        recover_leftovers(&parent, &name, target)?;
        if directory.staging.exists() {
            fs::remove_dir_all(&directory.staging)
                .map_err(|e| OutputError::io("removing", &directory.staging, e))?;
        }
        fs::create_dir(&directory.staging)
            .map_err(|e| OutputError::io("creating", &directory.staging, e))?;
        Ok(directory)
    }

    /// The staging directory, where the run writes its files.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The path of `name` in the staging directory.
    pub fn join(&self, name: impl AsRef<Path>) -> PathBuf {
        self.staging.join(name)
    }

    /// The target directory the results go to.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the staging directory to the target (replacing an old
    /// target whole when allowed, and putting the old one back if the
    /// rename fails) and releases the lock, all under [`UNCOMMITTED`].
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        let mut open = uncommitted();
        check_target(&self.target, self.replace)?;
        if is_empty_dir(&self.target) {
            fs::remove_dir(&self.target)
                .map_err(|e| OutputError::io("replacing", &self.target, e))?;
        }
        let replaced = self.target.exists();
        if replaced {
            let old = &self.old;
            if old.exists() {
                fs::remove_dir_all(old).map_err(|e| OutputError::io("removing", old, e))?;
            }
            fs::rename(&self.target, old)
                .map_err(|e| OutputError::io("moving aside", &self.target, e))?;
        }
        if let Err(error) = self.rename_staging() {
            if replaced {
                let _ = fs::rename(&self.old, &self.target);
            }
            return Err(error);
        }
        self.committed = true;
        open.retain(|(staging, _)| *staging != self.staging);
        let _ = fs::remove_file(&self.lock);
        drop(open);
        if replaced {
            fs::remove_dir_all(&self.old).map_err(|e| OutputError::io("removing", &self.old, e))?;
        }
        Ok(self.target.clone())
    }

    fn rename_staging(&self) -> Result<(), OutputError> {
        fs::rename(&self.staging, &self.target).map_err(|e| OutputError::Io {
            action: "renaming the finished results into",
            path: self.target.clone(),
            error: e,
        })
    }
}

impl Drop for OutputDirectory {
    /// Without a commit: removes the staging directory and the lock (a
    /// commit released the lock itself, which another run may hold now).
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        let mut open = uncommitted();
        open.retain(|(staging, _)| *staging != self.staging);
        let _ = fs::remove_dir_all(&self.staging);
        let _ = fs::remove_file(&self.lock);
    }
}

/// Whether `path` is a directory without entries.
fn is_empty_dir(path: &Path) -> bool {
    fs::read_dir(path).is_ok_and(|mut entries| entries.next().is_none())
}

/// The target may be written: missing, an empty directory, or (when
/// `replace`) any directory.
fn check_target(target: &Path, replace: bool) -> Result<(), OutputError> {
    match fs::metadata(target) {
        Err(_) => Ok(()),
        Ok(meta) if !meta.is_dir() => Err(OutputError::NotADirectory {
            path: target.to_path_buf(),
        }),
        Ok(_) if replace || is_empty_dir(target) => Ok(()),
        Ok(_) => Err(OutputError::NotEmpty {
            path: target.to_path_buf(),
        }),
    }
}

/// Creates the lock file exclusively and writes this process's id into
/// it; a lock left by a process that no longer runs is taken over once.
fn take_lock(target: &Path, lock: &Path) -> Result<(), OutputError> {
    for attempt in 0..2 {
        match OpenOptions::new().write(true).create_new(true).open(lock) {
            Ok(mut file) => {
                return write!(file, "{}", std::process::id())
                    .map_err(|e| OutputError::io("writing", lock, e));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let owner = fs::read_to_string(lock).unwrap_or_default();
                if attempt == 0 && is_stale(owner.trim(), lock) {
                    let _ = fs::remove_file(lock);
                    continue;
                }
                return Err(OutputError::Locked {
                    path: target.to_path_buf(),
                    lock: lock.to_path_buf(),
                    owner: owner.trim().to_string(),
                });
            }
            Err(e) => return Err(OutputError::io("creating the lock file", lock, e)),
        }
    }
    Err(OutputError::Locked {
        path: target.to_path_buf(),
        lock: lock.to_path_buf(),
        owner: "unknown".into(),
    })
}

/// How old an empty or unreadable lock file must be to be taken over (a
/// run writes its process id right after creating the file).
pub const UNREADABLE_LOCK_SECONDS: u64 = 10;

/// Whether the lock's owner is known not to run: a process id with no
/// `/proc` entry where `/proc` exists (Linux), or no process id at all in
/// a lock file older than [`UNREADABLE_LOCK_SECONDS`] (its run was killed
/// between creating it and writing its id).
fn is_stale(owner: &str, lock: &Path) -> bool {
    match owner.parse::<u32>() {
        Ok(pid) => !process_runs(pid).unwrap_or(true),
        Err(_) => fs::metadata(lock)
            .and_then(|meta| meta.modified())
            .ok()
            .and_then(|modified| modified.elapsed().ok())
            .is_some_and(|age| age.as_secs() >= UNREADABLE_LOCK_SECONDS),
    }
}

/// Whether process `pid` runs, where `/proc` can tell (Linux).
fn process_runs(pid: u32) -> Option<bool> {
    let proc = Path::new("/proc");
    proc.join("self")
        .exists()
        .then(|| proc.join(pid.to_string()).exists())
}

/// Cleans up after killed runs of `target` (in `parent`, named `name`),
/// with the lock held: removes their staging directories
/// (`.NAME.partial-PID`) and old results they moved aside
/// (`.NAME.old-PID`), except that old results are renamed back to the
/// target when it is missing (the run was killed between the two renames
/// of its commit). Directories of runs that may still run are left alone.
fn recover_leftovers(parent: &Path, name: &str, target: &Path) -> Result<(), OutputError> {
    let Ok(entries) = fs::read_dir(parent) else {
        return Ok(());
    };
    let (partial, old) = (format!(".{name}.partial-"), format!(".{name}.old-"));
    let mut leftovers: Vec<(PathBuf, bool)> = Vec::new();
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let (pid, is_old) = match (file.strip_prefix(&old), file.strip_prefix(&partial)) {
            (Some(pid), _) => (pid.to_string(), true),
            (None, Some(pid)) => (pid.to_string(), false),
            (None, None) => continue,
        };
        let dead = pid
            .parse::<u32>()
            .ok()
            .and_then(process_runs)
            .is_some_and(|runs| !runs);
        if dead {
            leftovers.push((entry.path(), is_old));
        }
    }
    for (path, is_old) in leftovers {
        if is_old && fs::symlink_metadata(target).is_err() {
            fs::rename(&path, target).map_err(|e| OutputError::Io {
                action: "restoring the results that a killed run had moved aside, from",
                path: path.clone(),
                error: e,
            })?;
        } else {
            fs::remove_dir_all(&path).map_err(|e| OutputError::io("removing", &path, e))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "posg-fsc-output-{name}-{}-{:?}",
            std::process::id(),
            std::thread::current().id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn results_appear_only_on_commit() {
        let base = scratch("commit");
        let target = base.join("out");
        let out = OutputDirectory::create(&target, false).unwrap();
        write_file(&out.join("a.txt"), "new").unwrap();
        assert!(!target.exists(), "nothing is visible before the commit");
        out.commit().unwrap();
        assert_eq!(fs::read_to_string(target.join("a.txt")).unwrap(), "new");
        let leftovers: Vec<_> = fs::read_dir(&base).unwrap().collect();
        assert_eq!(leftovers.len(), 1, "no staging directory or lock remains");
    }

    #[test]
    fn a_non_empty_target_is_refused_without_replace_and_replaced_whole_with_it() {
        let base = scratch("replace");
        let target = base.join("out");
        fs::create_dir_all(&target).unwrap();
        fs::write(target.join("old.txt"), "old").unwrap();
        assert!(matches!(
            OutputDirectory::create(&target, false),
            Err(OutputError::NotEmpty { .. })
        ));
        let out = OutputDirectory::create(&target, true).unwrap();
        write_file(&out.join("new.txt"), "new").unwrap();
        out.commit().unwrap();
        assert!(!target.join("old.txt").exists(), "never a mixture");
        assert_eq!(fs::read_to_string(target.join("new.txt")).unwrap(), "new");
    }

    #[test]
    fn an_abandoned_run_leaves_the_old_results_and_no_staging() {
        let base = scratch("abandon");
        let target = base.join("out");
        fs::create_dir_all(&target).unwrap();
        fs::write(target.join("old.txt"), "old").unwrap();
        {
            let out = OutputDirectory::create(&target, true).unwrap();
            write_file(&out.join("old.txt"), "").unwrap();
        }
        assert_eq!(fs::read_to_string(target.join("old.txt")).unwrap(), "old");
        assert_eq!(fs::read_dir(&base).unwrap().count(), 1);
    }

    #[test]
    fn a_second_writer_of_the_same_target_is_refused_until_the_first_ends() {
        let base = scratch("lock");
        let target = base.join("out");
        let first = OutputDirectory::create(&target, false).unwrap();
        let second = OutputDirectory::create(&target, false);
        assert!(
            matches!(&second, Err(OutputError::Locked { owner, .. }) if *owner == std::process::id().to_string()),
            "{second:?}"
        );
        drop(first);
        OutputDirectory::create(&target, false).unwrap();
    }

    #[test]
    fn a_lock_of_a_process_that_no_longer_runs_is_taken_over() {
        if !Path::new("/proc/self").exists() {
            return;
        }
        let base = scratch("stale");
        let target = base.join("out");
        fs::write(base.join(".out.lock"), u32::MAX.to_string()).unwrap();
        OutputDirectory::create(&target, false).unwrap();
    }

    #[test]
    fn a_kill_between_the_two_renames_is_recovered_by_the_next_force_run() {
        if !Path::new("/proc/self").exists() {
            return;
        }
        let base = scratch("kill-between-renames");
        let target = base.join("out");
        // A killed run (no such process) had moved the old results aside
        // and not yet renamed its staging directory.
        let dead = u32::MAX;
        fs::create_dir_all(base.join(format!(".out.old-{dead}"))).unwrap();
        fs::write(base.join(format!(".out.old-{dead}/a.txt")), "old").unwrap();
        fs::create_dir_all(base.join(format!(".out.partial-{dead}"))).unwrap();
        fs::write(base.join(format!(".out.partial-{dead}/a.txt")), "half").unwrap();
        // An earlier version's fixed name for the moved-aside results.
        fs::create_dir_all(base.join(".out.old")).unwrap();
        fs::write(base.join(".out.old/a.txt"), "older").unwrap();
        let out = OutputDirectory::create(&target, true).unwrap();
        assert_eq!(
            fs::read_to_string(target.join("a.txt")).unwrap(),
            "old",
            "the moved-aside results are back"
        );
        assert!(!base.join(format!(".out.partial-{dead}")).exists());
        write_file(&out.join("a.txt"), "new").unwrap();
        out.commit().unwrap();
        assert_eq!(fs::read_to_string(target.join("a.txt")).unwrap(), "new");
    }

    #[test]
    fn staging_directories_of_killed_runs_are_cleaned_up() {
        if !Path::new("/proc/self").exists() {
            return;
        }
        let base = scratch("killed-staging");
        let target = base.join("out");
        fs::create_dir_all(base.join(format!(".out.partial-{}", u32::MAX))).unwrap();
        let out = OutputDirectory::create(&target, false).unwrap();
        out.commit().unwrap();
        let names: Vec<String> = fs::read_dir(&base)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["out"]);
    }

    #[test]
    fn an_empty_lock_file_of_a_killed_run_is_taken_over() {
        let base = scratch("empty-lock");
        let target = base.join("out");
        let lock = base.join(".out.lock");
        let file = fs::File::create(&lock).unwrap();
        let long_ago = std::time::SystemTime::now()
            - std::time::Duration::from_secs(UNREADABLE_LOCK_SECONDS + 5);
        file.set_modified(long_ago).unwrap();
        drop(file);
        OutputDirectory::create(&target, false).unwrap();
        // A fresh empty lock (a run between creating it and writing its
        // id) is respected.
        let other = base.join("other");
        fs::File::create(base.join(".other.lock")).unwrap();
        assert!(matches!(
            OutputDirectory::create(&other, false),
            Err(OutputError::Locked { .. })
        ));
    }

    #[test]
    fn os_errors_are_printed_once() {
        let base = scratch("os-error-once");
        let file = base.join("plain-file");
        fs::write(&file, "x").unwrap();
        let error = create_dir(&file.join("sub")).unwrap_err();
        let chain: Vec<String> =
            std::iter::successors(Some(&error as &dyn std::error::Error), |e| e.source())
                .map(|e| e.to_string())
                .collect();
        let printed = chain.join(": ");
        assert_eq!(printed.matches("os error").count(), 1, "{printed}");
    }

    #[test]
    fn errors_name_the_path() {
        let base = scratch("errors");
        let file = base.join("plain-file");
        fs::write(&file, "x").unwrap();
        let error = OutputDirectory::create(&file, true).unwrap_err();
        assert!(error.to_string().contains("plain-file"), "{error}");
        let error = write_file(&base.join("missing/dir/a.txt"), "x").unwrap_err();
        assert!(error.to_string().contains("missing/dir/a.txt"), "{error}");
    }
}
