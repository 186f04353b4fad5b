//! What the benches share: the shared test meshes, found beside the clone or through
//! `WAVEMILL_TESTDATA`, and prepared (welded, oriented) as the commands prepare them.

use wavemill::job;
use wavemill::mesh::{Mesh, PrepareOptions, prepare};

/// The shared test mesh at `meshes/<file>` in `units`, prepared; `None` (with a `skipped:`
/// line) when the shared test data is absent.
pub fn shared_mesh(file: &str, units: &str) -> Option<Mesh> {
    let path = std::env::var_os("WAVEMILL_TESTDATA")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata")
        })
        .join("meshes")
        .join(file);
    if !path.is_file() {
        eprintln!("skipped: {} not found", path.display());
        return None;
    }
    let raw = job::load_part(&path, units).expect("a shared test mesh loads");
    Some(
        prepare(&raw.mesh, &PrepareOptions::default())
            .expect("a shared test mesh prepares")
            .0,
    )
}
