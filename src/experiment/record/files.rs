//! The names of the files a results directory holds, in one place: the run writes them, the
//! results room reads them back, and `raylab summary`/`report` find them by these names.

/// One row per measurement (`run_row::RunRow`).
pub const RUNS_CSV: &str = "runs.csv";
/// Box and triangle tests per BVH depth, for the ray batches.
pub const HISTOGRAMS_CSV: &str = "histograms.csv";
/// One row per sampled check of a tracer against the oracle.
pub const VERIFY_CSV: &str = "verify.csv";
/// Commit, CPU, ISA, library versions, the experiment file and the plan.
pub const META_JSON: &str = "meta.json";
/// The experiment's paper-vs-ours tables.
pub const TABLES_MD: &str = "tables.md";
/// The run's summary, recomputed from the files above.
pub const SUMMARY_MD: &str = "summary.md";
/// The stability suite's rows (an experiment with `[stability]`).
pub const STABILITY_CSV: &str = "stability.csv";
/// A shard's heat-map panels (`heatmap_file`), drawn by `raylab merge`.
pub const HEATMAPS_BIN: &str = "heatmaps.bin";
/// Where `--dump-rays` writes the generated batches.
pub const RAYS_DIR: &str = "rays";

/// The suffix of a results file kept compressed (a committed runs.csv of several MiB, say): every
/// reader of `name` reads `name` + this, gzip, as if it were `name` (`read_text`).
pub const GZIP_SUFFIX: &str = ".gz";

/// The text of results file `path`, or of its gzip-compressed copy `path.gz` when `path` itself
/// is not there; `None` when neither is.
pub fn read_text(path: &std::path::Path) -> crate::error::Result<Option<String>> {
    use std::io::Read;
    match std::fs::read_to_string(path) {
        Ok(text) => return Ok(Some(text)),
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(crate::error::Error::io(path, e))
        }
        Err(_) => {}
    }
    let mut packed = path.as_os_str().to_owned();
    packed.push(GZIP_SUFFIX);
    let packed = std::path::PathBuf::from(packed);
    let file = match std::fs::File::open(&packed) {
        Ok(file) => file,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(crate::error::Error::io(&packed, e)),
    };
    let mut text = String::new();
    flate2::read::GzDecoder::new(file)
        .read_to_string(&mut text)
        .map_err(|e| crate::error::Error::input(&packed, None, format!("not gzip text: {e}")))?;
    Ok(Some(text))
}

/// Whether results file `path` is there, plain or compressed (`read_text`).
pub fn exists(path: &std::path::Path) -> bool {
    let mut packed = path.as_os_str().to_owned();
    packed.push(GZIP_SUFFIX);
    path.is_file() || std::path::Path::new(&packed).is_file()
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    /// A compressed results file reads as the plain one; a missing one as none; a `.gz` that is
    /// not gzip is an error naming it.
    #[test]
    fn a_compressed_results_file_reads_as_the_plain_one() {
        let dir = std::env::temp_dir().join(format!("raylab-gz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = "scene,rays\nroom,1024\n";
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        gz.write_all(text.as_bytes()).unwrap();
        std::fs::write(dir.join("runs.csv.gz"), gz.finish().unwrap()).unwrap();
        assert!(exists(&dir.join(RUNS_CSV)));
        assert_eq!(
            read_text(&dir.join(RUNS_CSV)).unwrap().as_deref(),
            Some(text)
        );
        assert!(!exists(&dir.join(VERIFY_CSV)));
        assert_eq!(read_text(&dir.join(VERIFY_CSV)).unwrap(), None);
        std::fs::write(dir.join("verify.csv.gz"), "plain").unwrap();
        let err = read_text(&dir.join(VERIFY_CSV)).unwrap_err().to_string();
        assert!(err.contains("verify.csv.gz"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
