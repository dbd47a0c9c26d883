//! Writing the `.fmu` (a zip archive with forward-slash paths, deflated).

use std::io::Write;
use std::path::{Path, PathBuf};

use zip::write::SimpleFileOptions;

/// Writes an FMU with each `(path inside the archive, file)` of `binaries`.
pub fn write_fmu(
    path: &Path,
    binaries: &[(String, PathBuf)],
    model_description: &str,
    documentation: &str,
) -> Result<(), String> {
    let mut contents = vec![];
    for (_, library) in binaries {
        contents.push(std::fs::read(library).map_err(|e| format!("cannot read {}: {e}", library.display()))?);
    }
    let file = std::fs::File::create(path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let text = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let executable = text.unix_permissions(0o755);
    let mut entries: Vec<(&str, &[u8], SimpleFileOptions)> =
        vec![("modelDescription.xml", model_description.as_bytes(), text)];
    for ((inside, _), bytes) in binaries.iter().zip(&contents) {
        entries.push((inside, bytes, executable));
    }
    entries.push(("documentation/index.html", documentation.as_bytes(), text));
    for (name, bytes, options) in entries {
        zip.start_file(name, options).map_err(|e| format!("zip {name}: {e}"))?;
        zip.write_all(bytes).map_err(|e| format!("zip {name}: {e}"))?;
    }
    zip.finish().map_err(|e| format!("cannot finish {}: {e}", path.display()))?;
    Ok(())
}

/// Writes an SSP archive: `SystemStructure.ssd` and the FMUs under `resources/`.
pub fn write_ssp(path: &Path, ssd: &str, fmus: &[&Path]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let options = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    zip.start_file("SystemStructure.ssd", options).map_err(|e| format!("zip: {e}"))?;
    zip.write_all(ssd.as_bytes()).map_err(|e| format!("zip: {e}"))?;
    for fmu in fmus {
        let name = fmu.file_name().and_then(|n| n.to_str()).ok_or("bad FMU file name")?;
        let bytes = std::fs::read(fmu).map_err(|e| format!("cannot read {}: {e}", fmu.display()))?;
        // Already compressed: store.
        let stored = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
        zip.start_file(format!("resources/{name}"), stored).map_err(|e| format!("zip: {e}"))?;
        zip.write_all(&bytes).map_err(|e| format!("zip: {e}"))?;
    }
    zip.finish().map_err(|e| format!("cannot finish {}: {e}", path.display()))?;
    Ok(())
}
