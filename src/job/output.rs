//! Writing outputs so that a reader never sees a half-written file or a mixed set.
//!
//! A single file is written to a temporary file in the same folder, flushed, then renamed over
//! the target (atomic on one filesystem). A command's whole output set (`job.nc` with the
//! `cl.csv` and `report.json` that describe it, every `level-<j>.glb` of one run, …) is written
//! into a hidden staging folder beside the output folder and then swapped in for it by two
//! renames: whatever happens (a full disk, a kill), the output folder holds either the
//! complete old set or the complete new one, never a new `job.nc` beside an older report, and
//! never a stale `level-2.glb` from an earlier, larger run. A kill between the two renames
//! leaves the old set in a hidden `.old` folder and the folder itself missing, not mixed; the
//! next run clears such leftovers.
//!
//! Because the folder is replaced whole, it may hold only the files the command writes: a
//! folder with anything else in it is refused before any work is done
//! ([`check_output_dir`]), so no file of the user's is ever removed.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::pipeline::PlanOutput;
use crate::error::{Error, Result};

/// Writes `bytes` to `path` through a temporary file and a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |source| Error::Io {
        path: path.display().to_string(),
        source,
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// The files one command writes into its output folder.
#[derive(Clone, Copy, Debug)]
pub struct OutputKind {
    /// The command, for messages.
    pub command: &'static str,
    /// Whether a file name in the output folder is one of this command's outputs.
    owns: fn(&str) -> bool,
}

/// Whether `name` is `prefix<digits>suffix`.
fn numbered(name: &str, prefix: &str, suffix: &str) -> bool {
    name.strip_prefix(prefix)
        .and_then(|rest| rest.strip_suffix(suffix))
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

impl OutputKind {
    pub const PLAN: OutputKind = OutputKind {
        command: "plan",
        owns: |n| {
            matches!(
                n,
                "job.nc"
                    | "cl.csv"
                    | "cl.apt"
                    | "report.json"
                    | "paths.glb"
                    | "scallop.glb"
                    | "scallop.png"
            ) || numbered(n, "stock-", ".glb")
        },
    };
    pub const LEVELS: OutputKind = OutputKind {
        command: "levels",
        owns: |n| n == "levels.json" || numbered(n, "level-", ".glb"),
    };
    pub const OFFSETS: OutputKind = OutputKind {
        command: "offsets",
        owns: |n| n == "offsets.json" || numbered(n, "offset-", ".glb"),
    };
    pub const ACCESS: OutputKind = OutputKind {
        command: "access",
        owns: |n| matches!(n, "access.glb" | "access.json" | "query.csv"),
    };
    pub const SIMULATE: OutputKind = OutputKind {
        command: "simulate",
        owns: |n| matches!(n, "simulation.json" | "stock.glb" | "stock.png"),
    };
    pub const ROUGH: OutputKind = OutputKind {
        command: "rough",
        owns: |n| matches!(n, "rough.nc" | "cl.csv" | "rough.json" | "stock.glb"),
    };
    pub const TOOLS: OutputKind = OutputKind {
        command: "tools",
        owns: |n| matches!(n, "tools.glb" | "tools.json"),
    };
    pub const CONTOUR: OutputKind = OutputKind {
        command: "contour",
        owns: |n| {
            matches!(
                n,
                "wavelet.nc" | "contour_parallel.nc" | "compare.json" | "paths.svg" | "paths.png"
            )
        },
    };

    pub const LENS: OutputKind = OutputKind {
        command: "lens",
        owns: |n| {
            matches!(
                n,
                "grid.csv" | "grid.bin" | "lens.nc" | "lens.json" | "lens.png" | "offset.igs"
            )
        },
    };

    /// Whether `name` is one of this command's outputs.
    pub fn owns(&self, name: &str) -> bool {
        (self.owns)(name)
    }
}

/// The hidden sibling folders an output set is staged in and the old set is moved to.
fn staging_dirs(dir: &Path) -> Result<(PathBuf, PathBuf, PathBuf)> {
    let name = dir
        .file_name()
        .filter(|n| *n != ".." && *n != ".")
        .ok_or_else(|| {
            Error::Usage(format!(
                "output folder {}: name a folder, not `.`, `..` or a root",
                dir.display()
            ))
        })?
        .to_string_lossy()
        .into_owned();
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let pid = std::process::id();
    Ok((
        parent.join(format!(".{name}.wavemill-{pid}.new")),
        parent.join(format!(".{name}.wavemill-{pid}.old")),
        parent,
    ))
}

/// Removes staging and old folders that earlier runs for `dir` left behind when they were
/// killed (their process is gone). Where processes cannot be looked up, nothing is removed.
fn clear_leftovers(dir: &Path, parent: &Path) {
    let Some(name) = dir.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return;
    };
    let proc = Path::new("/proc");
    if !proc.is_dir() {
        return;
    }
    let prefix = format!(".{name}.wavemill-");
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&prefix) else {
            continue;
        };
        let Some(pid) = rest
            .strip_suffix(".new")
            .or_else(|| rest.strip_suffix(".old"))
        else {
            continue;
        };
        if pid.bytes().all(|b| b.is_ascii_digit()) && !proc.join(pid).exists() {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// Checks, before any work, that `dir` can take `kind`'s output set: it is a folder (or can be
/// made one) holding nothing but `kind`'s outputs, and its parent folder can be written to.
pub fn check_output_dir(dir: &Path, kind: &OutputKind) -> Result<()> {
    let shown = dir.display().to_string();
    let (staging, _, parent) = staging_dirs(dir)?;
    match std::fs::symlink_metadata(dir) {
        Ok(meta) if !meta.is_dir() => {
            return Err(Error::Usage(format!(
                "output folder {shown} exists and is not a folder"
            )));
        }
        Ok(_) => {
            let entries = std::fs::read_dir(dir).map_err(|source| Error::Io {
                path: shown.clone(),
                source,
            })?;
            let mut foreign: Vec<String> = entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| !kind.owns(n))
                .collect();
            if !foreign.is_empty() {
                foreign.sort();
                let more = foreign.len().saturating_sub(3);
                foreign.truncate(3);
                return Err(Error::Usage(format!(
                    "output folder {shown} holds files `wavemill {}` does not write ({}{}): \
                     it replaces the folder's contents as a whole, so give it a new or empty \
                     folder, or one of its own earlier runs",
                    kind.command,
                    foreign.join(", "),
                    if more > 0 {
                        format!(" and {more} more")
                    } else {
                        String::new()
                    }
                )));
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(source) => {
            return Err(Error::Io {
                path: shown,
                source,
            });
        }
    }
    std::fs::create_dir_all(&parent).map_err(|source| Error::Io {
        path: parent.display().to_string(),
        source,
    })?;
    clear_leftovers(dir, &parent);
    // Probe: the parent must take the staging folder.
    let _ = std::fs::remove_dir_all(&staging);
    std::fs::create_dir(&staging).map_err(|source| Error::Io {
        path: parent.display().to_string(),
        source,
    })?;
    let _ = std::fs::remove_dir(&staging);
    Ok(())
}

/// Replaces the contents of `dir` with `files` (name, bytes) as one set (see the module docs).
pub fn write_output_set(dir: &Path, kind: &OutputKind, files: &[(String, Vec<u8>)]) -> Result<()> {
    check_output_dir(dir, kind)?;
    if let Some((name, _)) = files.iter().find(|(n, _)| !kind.owns(n)) {
        return Err(Error::Internal(format!(
            "internal: `wavemill {}` would write {name}, which it does not own",
            kind.command
        )));
    }
    let (staging, old, _) = staging_dirs(dir)?;
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |source| Error::Io { path, source }
    };
    let staged = (|| -> Result<()> {
        std::fs::create_dir(&staging).map_err(io(&staging))?;
        for (name, bytes) in files {
            let path = staging.join(name);
            let mut f = std::fs::File::create(&path).map_err(io(&path))?;
            f.write_all(bytes).map_err(io(&path))?;
            f.sync_all().map_err(io(&path))?;
        }
        Ok(())
    })();
    if let Err(e) = staged {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(e);
    }
    let had_old = dir.exists();
    if had_old && let Err(source) = std::fs::rename(dir, &old) {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(Error::Io {
            path: dir.display().to_string(),
            source,
        });
    }
    if let Err(source) = std::fs::rename(&staging, dir) {
        if had_old {
            let _ = std::fs::rename(&old, dir);
        }
        let _ = std::fs::remove_dir_all(&staging);
        return Err(Error::Io {
            path: dir.display().to_string(),
            source,
        });
    }
    if had_old {
        let _ = std::fs::remove_dir_all(&old);
    }
    Ok(())
}

/// `value` as pretty JSON with a final newline.
pub(crate) fn json_bytes(name: &str, value: &impl serde::Serialize) -> Result<Vec<u8>> {
    Ok((serde_json::to_string_pretty(value)
        .map_err(|e| Error::Internal(format!("{name}: {e}")))?
        + "\n")
        .into_bytes())
}

/// Writes `job.nc`, `cl.csv`, `cl.apt`, `report.json`, `paths.glb`, `scallop.glb` and
/// `scallop.png` (what the finishing leaves) and, with a `[stock]` blank, the
/// `stock-N.glb` after each operation into `dir` as one set (see the module docs). With `timings = false` the report leaves out the per-stage timings, the only
/// part of the outputs that differs between runs. A path that failed verification gets only
/// its report (for diagnosis; the folder then holds nothing else) and an
/// [`Error::Verification`].
pub fn write_outputs(dir: &Path, output: &PlanOutput, timings: bool) -> Result<()> {
    let report = (
        "report.json".to_string(),
        output.report.to_json(timings).into_bytes(),
    );
    if let Some(problem) = &output.verification_failure {
        write_output_set(dir, &OutputKind::PLAN, &[report])?;
        return Err(Error::Verification(format!(
            "{problem} (see {})",
            dir.join("report.json").display()
        )));
    }
    let mut files = vec![
        ("job.nc".into(), output.gcode.clone().into_bytes()),
        ("cl.csv".into(), output.cl_csv.clone().into_bytes()),
        ("cl.apt".into(), output.cl_apt.clone().into_bytes()),
        ("paths.glb".into(), output.preview_glb.clone()),
        report,
    ];
    files.extend(output.scallop_pictures.iter().cloned());
    files.extend(output.stock_models.iter().cloned());
    write_output_set(dir, &OutputKind::PLAN, &files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp_files() {
        let dir = std::env::temp_dir().join(format!("wavemill-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("a.txt");
        write_atomically(&target, b"first").unwrap();
        write_atomically(&target, b"second").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"second");
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
        // A folder that does not exist: an error naming the path, no panic.
        let e = write_atomically(&dir.join("missing/b.txt"), b"x").unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut n: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        n.sort();
        n
    }

    fn set(names: &[&str], content: &str) -> Vec<(String, Vec<u8>)> {
        names
            .iter()
            .map(|n| (n.to_string(), content.as_bytes().to_vec()))
            .collect()
    }

    /// Issue 17 item 6: `levels` left a stale `level-2.glb` from an earlier, larger run, and a
    /// failed write left a new file beside older ones. The set is replaced whole, nothing else
    /// is left beside the folder, and a write that fails leaves the old set as it was.
    #[test]
    fn an_output_set_replaces_the_old_one_whole() {
        let parent = std::env::temp_dir().join(format!("wavemill-set-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&parent);
        std::fs::create_dir_all(&parent).unwrap();
        let dir = parent.join("out");
        let kind = OutputKind::LEVELS;
        let big = set(
            &["level-0.glb", "level-1.glb", "level-2.glb", "levels.json"],
            "a",
        );
        write_output_set(&dir, &kind, &big).unwrap();
        assert_eq!(names(&dir).len(), 4);
        write_output_set(&dir, &kind, &set(&["level-0.glb", "levels.json"], "b")).unwrap();
        assert_eq!(names(&dir), ["level-0.glb", "levels.json"]);
        assert_eq!(std::fs::read(dir.join("levels.json")).unwrap(), b"b");
        assert_eq!(names(&parent), ["out"], "no staging folders left");

        // A failure while staging (the staging name is taken by a file): the error names the
        // place, the old set is untouched.
        let (staging, _, _) = staging_dirs(&dir).unwrap();
        std::fs::write(&staging, "in the way").unwrap();
        let e = write_output_set(&dir, &kind, &big).unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
        assert_eq!(names(&dir), ["level-0.glb", "levels.json"]);
        assert_eq!(std::fs::read(dir.join("levels.json")).unwrap(), b"b");
        std::fs::remove_file(&staging).unwrap();

        // A file the command does not write makes the folder unusable, before any work.
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        let e = check_output_dir(&dir, &kind).unwrap_err();
        assert!(e.to_string().contains("notes.txt"), "{e}");
        assert_eq!(e.exit_code(), 2);
        assert!(write_output_set(&dir, &kind, &big).is_err());
        assert_eq!(std::fs::read(dir.join("notes.txt")).unwrap(), b"mine");
        // Nor may it be a file.
        let e = check_output_dir(&dir.join("notes.txt"), &kind).unwrap_err();
        assert!(e.to_string().contains("not a folder"), "{e}");
        std::fs::remove_dir_all(&parent).unwrap();
    }

    #[test]
    fn each_command_owns_only_its_own_files() {
        assert!(OutputKind::LEVELS.owns("level-12.glb"));
        assert!(!OutputKind::LEVELS.owns("level-.glb") && !OutputKind::LEVELS.owns("level-1.obj"));
        assert!(OutputKind::OFFSETS.owns("offset-0.glb") && !OutputKind::OFFSETS.owns("job.nc"));
        assert!(OutputKind::PLAN.owns("job.nc") && !OutputKind::PLAN.owns("levels.json"));
    }
}
