//! Writing outputs so that a reader never sees a half-written file: write a temporary file in
//! the same folder, flush it, then rename it over the target (atomic on one filesystem).

use std::io::Write;
use std::path::Path;

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

/// Creates the output folder `dir` (and its parents) if missing.
pub(crate) fn create_output_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.display().to_string(),
        source,
    })
}

/// Writes `value` as pretty JSON with a final newline to `dir/name`, atomically.
pub(crate) fn write_json(dir: &Path, name: &str, value: &impl serde::Serialize) -> Result<()> {
    let json =
        serde_json::to_string_pretty(value).map_err(|e| Error::Job(format!("{name}: {e}")))? + "\n";
    write_atomically(&dir.join(name), json.as_bytes())
}

/// Writes `job.nc`, `cl.csv`, `report.json` and `paths.glb` into `dir` (created if missing).
/// With `timings = false` the report leaves out the per-stage timings, the only part of the
/// outputs that differs between runs. A path that failed verification gets only its report
/// (for diagnosis) and an [`Error::Verification`].
pub fn write_outputs(dir: &Path, output: &PlanOutput, timings: bool) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.display().to_string(),
        source,
    })?;
    if let Some(problem) = &output.verification_failure {
        for stale in ["job.nc", "cl.csv", "paths.glb"] {
            let _ = std::fs::remove_file(dir.join(stale));
        }
        write_atomically(
            &dir.join("report.json"),
            output.report.to_json(timings).as_bytes(),
        )?;
        return Err(Error::Verification(format!(
            "{problem} (see {})",
            dir.join("report.json").display()
        )));
    }
    write_atomically(&dir.join("job.nc"), output.gcode.as_bytes())?;
    write_atomically(&dir.join("cl.csv"), output.cl_csv.as_bytes())?;
    write_atomically(&dir.join("paths.glb"), &output.preview_glb)?;
    write_atomically(
        &dir.join("report.json"),
        output.report.to_json(timings).as_bytes(),
    )?;
    Ok(())
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
}
