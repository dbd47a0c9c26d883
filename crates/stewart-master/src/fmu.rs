//! An FMU unpacked once into a temporary folder of its own, its model description read and the
//! binary of the platform the master runs on loaded; instances are made from it as often as
//! needed. The folder is removed when the `Fmu` is dropped.

use std::io::{Cursor, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::description::ModelDescription;
use crate::fmi2::{Instance, Library};

/// A folder under the system's temporary folder, removed on drop.
struct TempDir(PathBuf);

static FOLDERS: AtomicUsize = AtomicUsize::new(0);

impl TempDir {
    fn new(label: &str) -> Result<TempDir, String> {
        let base = std::env::temp_dir();
        let label: String = label.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).take(40).collect();
        let nanos =
            std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.subsec_nanos()).unwrap_or(0);
        for attempt in 0..100 {
            let n = FOLDERS.fetch_add(1, Ordering::Relaxed);
            let path = base.join(format!("stewart-master-{label}-{}-{n}-{nanos}-{attempt}", std::process::id()));
            match std::fs::create_dir(&path) {
                Ok(()) => return Ok(TempDir(path)),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(format!("cannot create a folder in {} to unpack the FMU: {e}", base.display())),
            }
        }
        Err(format!("cannot create a new folder in {}", base.display()))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

pub struct Fmu {
    pub description: ModelDescription,
    /// Where the FMU came from, for messages.
    pub label: String,
    library: Arc<Library>,
    resource_uri: String,
    // Last: removed after the library's last handle here is gone.
    folder: TempDir,
}

/// The FMI 2 binary folder of the platform the master is built for, the binary's extension and
/// the platform's name in messages. FMI 2 names one folder for 64-bit Linux whatever the
/// processor, as FMPy and FMI Library read it: an FMU for aarch64 Linux carries its aarch64
/// binary in `linux64` (the aarch64 wheel's FMI 2 FMUs do; the repository's carry x86-64).
#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
const PLATFORM: (&str, &str, &str) = ("linux64", "so", "Linux x86-64");
#[cfg(all(target_os = "linux", target_arch = "aarch64"))]
const PLATFORM: (&str, &str, &str) = ("linux64", "so", "Linux aarch64");
#[cfg(all(windows, target_arch = "x86_64"))]
const PLATFORM: (&str, &str, &str) = ("win64", "dll", "Windows x64");
#[cfg(not(any(
    all(target_os = "linux", any(target_arch = "x86_64", target_arch = "aarch64")),
    all(windows, target_arch = "x86_64")
)))]
compile_error!("stewart-master loads FMU binaries on Linux x86-64 and aarch64 and on Windows x64 only");

impl Fmu {
    pub fn from_path(path: &Path) -> Result<Fmu, String> {
        let data = std::fs::read(path).map_err(|e| format!("cannot read the FMU {}: {e}", path.display()))?;
        Fmu::from_bytes(&data, &path.display().to_string())
    }

    /// Unpacks an FMU given as the bytes of its zip archive (`label` names it in messages).
    pub fn from_bytes(data: &[u8], label: &str) -> Result<Fmu, String> {
        let mut archive = zip::ZipArchive::new(Cursor::new(data))
            .map_err(|e| format!("{label} is not an FMU (a zip archive): {e}"))?;
        let stem = Path::new(label).file_stem().and_then(|s| s.to_str()).unwrap_or("fmu").to_string();
        let folder = TempDir::new(&stem)?;
        // `extract` refuses entries whose names leave the folder.
        archive.extract(&folder.0).map_err(|e| format!("cannot unpack {label}: {e}"))?;
        let xml = std::fs::read_to_string(folder.0.join("modelDescription.xml"))
            .map_err(|e| format!("{label} has no readable modelDescription.xml: {e}"))?;
        let description = ModelDescription::parse(&xml).map_err(|e| format!("{label}: {e}"))?;
        let (platform, extension, platform_name) = PLATFORM;
        let file = format!("{}.{extension}", description.model_identifier);
        let binary = folder.0.join("binaries").join(platform).join(&file);
        if !binary.is_file() {
            return Err(format!("{label} has no binary for {platform_name} (binaries/{platform}/{file})"));
        }
        let library = Arc::new(Library::load(&binary)?);
        let resource_uri = file_uri(&folder.0.join("resources"));
        Ok(Fmu { description, label: label.to_string(), library, resource_uri, folder })
    }

    /// A new instance (`fmi2Instantiate`).
    pub fn instantiate(&self, name: &str) -> Result<Instance, String> {
        Instance::new(self.library.clone(), name, &self.description.guid, &self.resource_uri)
    }

    /// The folder it was unpacked into.
    pub fn folder(&self) -> &Path {
        &self.folder.0
    }
}

/// An absolute path as a file URI (RFC 8089): `file:///home/...`, on Windows `file:///C:/...`.
fn file_uri(path: &Path) -> String {
    let text = path.to_string_lossy().into_owned();
    #[cfg(windows)]
    let text = text.replace('\\', "/");
    let slash = if text.starts_with('/') { "" } else { "/" };
    format!("file://{slash}{}", percent_encode(&text))
}

/// A path as a file URI's path (RFC 3986: unreserved characters, `/` and a drive's `:` stay).
fn percent_encode(path: &str) -> String {
    let mut out = String::with_capacity(path.len());
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~:".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// One file of a zip archive (an SSP's SystemStructure.ssd or one of its FMUs).
pub fn read_from_zip(data: &[u8], name: &str, label: &str) -> Result<Vec<u8>, String> {
    let mut archive =
        zip::ZipArchive::new(Cursor::new(data)).map_err(|e| format!("{label} is not a zip archive: {e}"))?;
    let mut file = archive.by_name(name).map_err(|e| format!("{label} has no {name}: {e}"))?;
    let mut out = Vec::with_capacity(file.size() as usize);
    file.read_to_end(&mut out).map_err(|e| format!("cannot read {name} in {label}: {e}"))?;
    Ok(out)
}
