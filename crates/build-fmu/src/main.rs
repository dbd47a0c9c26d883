//! `cargo run --release --bin build-fmu [-- --targets LIST] [--update-model-description]`:
//! builds the FMU binary for every target platform and packages `target/fmu/<ModelIdentifier>.fmu`
//! (FMI 2.0) for every model in the crate and `target/fmu/fmi3/<ModelIdentifier>.fmu`
//! (FMI 3.0) for the product models, each FMU carrying the binaries of all the platforms built.
//!
//! Steps, each of which stops the build with a clear message when it fails:
//! 1. build the FMU crate's library for every target at once (`platforms.rs`: this machine's with its
//!    own toolchain, the others with an installed target or with the standard library compiled
//!    from source, and the target's linker);
//! 2. check each binary from its file (`file_check.rs`): the FMI functions exported and
//!    nothing else, no maths imported from the system's C library, only system libraries
//!    needed;
//! 3. compare `modelDescription/<id>.xml` and `modelDescription/fmi3/<id>.xml` with what the
//!    variable tables generate (`--update-model-description` rewrites them);
//! 4. check the XML with quick-xml: well-formed, unique names and value references,
//!    ModelStructure valid and complete, units defined, start values sized;
//! 5. load this machine's binary with `dlopen` and check that it accepts the XML's GUID or
//!    token (and refuses another);
//! 6. zip `modelDescription.xml`, the binaries (FMI 2 `binaries/linux64/<id>.so`,
//!    `binaries/win64/<id>.dll`; FMI 3 `binaries/x86_64-linux/<id>.so`, `aarch64-linux`,
//!    `x86_64-windows`) and `documentation/index.html`;
//! 7. check `modelDescription/StewartSystem.ssd` (the closed loop) and
//!    `StewartSystemDrives.ssd` (with electric drives) against the models and zip each with
//!    both FMI 2 FMUs into `target/fmu/StewartSystem.ssp`, `StewartSystemDrives.ssp`.

mod binary_check;
mod file_check;
mod package;
mod platforms;
mod ssd_check;
mod xml_check;
mod xml_check3;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use stewart_fmu::fmi::FmiVersion;
use stewart_fmu::fmi::description::{
    documentation_html, instantiation_token, model_description_xml, with_interface_table,
};
use stewart_fmu::models::ModelKind;

use platforms::Platform;

const USAGE: &str = "usage: build-fmu [--targets x86_64-linux,aarch64-linux,x86_64-windows,x86_64-darwin,aarch64-darwin|all] \
                     [--update-model-description]";

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("build-fmu: error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// A binary built for one platform.
struct Binary {
    platform: &'static Platform,
    path: PathBuf,
}

fn run() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let (mut update, mut targets) = (false, None);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--update-model-description" => update = true,
            "--targets" => targets = Some(args.next().ok_or(format!("--targets needs a list ({USAGE})"))?),
            "--help" | "-h" => {
                println!("{USAGE}");
                println!("default targets: {}", default_names());
                return Ok(());
            }
            other => match other.strip_prefix("--targets=") {
                Some(list) => targets = Some(list.to_string()),
                None => return Err(format!("unknown argument {other} ({USAGE})")),
            },
        }
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().map_err(|e| e.to_string())?;
    // Absolute: the nested builds run in the repository's root, whatever this one's folder.
    let target_dir = match std::env::var("CARGO_TARGET_DIR") {
        Ok(dir) => std::env::current_dir().map_err(|e| e.to_string())?.join(dir),
        Err(_) => root.join("target"),
    };

    let platforms = platforms::selected(targets.as_deref())?;
    let binaries = build_binaries(&platforms, &root, &target_dir)?;
    let native = binaries.iter().find(|b| b.platform.triple == platforms::host_triple()).map(|b| b.path.clone());
    if native.is_none() {
        println!(
            "build-fmu: this machine's platform ({}) is not among the targets: no binary is loaded to check its tokens",
            platforms::host_triple()
        );
    }

    let out_dir = target_dir.join("fmu");
    std::fs::create_dir_all(&out_dir).map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    for kind in ModelKind::ALL {
        build_one(kind, &root, native.as_deref(), &binaries, &out_dir, update)?;
    }
    for kind in ModelKind::ALL.into_iter().filter(|k| !k.is_benchmark_floor()) {
        build_one_fmi3(kind, &root, native.as_deref(), &binaries, &out_dir.join("fmi3"), update)?;
    }

    interface_tables(&root.join("docs").join("model.md"), update)?;

    // The closed loop with force commands, with electric drives (voltage commands) and with
    // hydraulic servo legs (valve commands), the same fed by the power unit with the safe
    // landing; the whole motion system with the cueing FMU.
    for system in [
        "StewartSystem",
        "StewartSystemDrives",
        "StewartSystemHydraulic",
        "StewartSystemPowerUnit",
        "StewartMotionSystem",
    ] {
        let ssd_path = root.join("modelDescription").join(format!("{system}.ssd"));
        let ssd = std::fs::read_to_string(&ssd_path).map_err(|e| format!("cannot read {}: {e}", ssd_path.display()))?;
        let sources = ssd_check::check(&ssd).map_err(|e| format!("{}: {e}", ssd_path.display()))?;
        let fmus: Vec<PathBuf> = sources.iter().map(|s| out_dir.join(s)).collect();
        let ssp = out_dir.join(format!("{system}.ssp"));
        if let Some(missing) = fmus.iter().find(|f| !f.exists()) {
            println!(
                "build-fmu: {system}: {} was not built (no FMI 2 platform among the targets), no SSP",
                missing.display()
            );
            let _ = std::fs::remove_file(&ssp);
            continue;
        }
        let fmu_refs: Vec<&Path> = fmus.iter().map(|p| p.as_path()).collect();
        package::write_ssp(&ssp, &ssd, &fmu_refs)?;
        println!("build-fmu: {system} ({} components) -> {}", fmus.len(), ssp.display());
    }
    Ok(())
}

fn default_names() -> String {
    platforms::PLATFORMS.iter().filter(|p| p.by_default).map(|p| p.name).collect::<Vec<_>>().join(",")
}

/// Builds the FMU crate's library for every platform at once and checks each file. Each build
/// compiles the FMU crate in one codegen unit (one core) in a target folder of its own, so
/// they run side by side; each writes its output to `<target>/build-logs/<platform>.log`, and
/// a line says when each is done (or the log's end, when it failed).
fn build_binaries(targets: &[&'static Platform], root: &Path, target_dir: &Path) -> Result<Vec<Binary>, String> {
    // Every command first: a platform that cannot be built here stops everything before any starts.
    let builds = targets
        .iter()
        .map(|&platform| platforms::build_command(platform, root, target_dir).map(|build| (platform, build)))
        .collect::<Result<Vec<_>, String>>()?;
    let log_dir = target_dir.join("build-logs");
    std::fs::create_dir_all(&log_dir).map_err(|e| format!("cannot create {}: {e}", log_dir.display()))?;
    let started = Instant::now();
    let mut running = vec![];
    for (platform, mut build) in builds {
        let log_path = log_dir.join(format!("{}.log", platform.name));
        let log = std::fs::File::create(&log_path).map_err(|e| format!("cannot create {}: {e}", log_path.display()))?;
        let log_too = log.try_clone().map_err(|e| format!("{}: {e}", log_path.display()))?;
        println!(
            "build-fmu: {}: building the FMU binary ({}; minutes the first time, seconds when nothing changed; {})",
            platform.name,
            build.how,
            log_path.display()
        );
        let child = build.command.stdout(log).stderr(log_too).spawn();
        match child {
            Ok(child) => running.push((platform, build, log_path, child)),
            Err(e) => {
                stop_builds(&mut running);
                return Err(format!("{}: cannot run {:?}: {e}", platform.name, build.command.get_program()));
            }
        }
    }
    let mut binaries = vec![];
    let mut failures = vec![];
    while !running.is_empty() {
        let mut index = 0;
        while index < running.len() {
            let (platform, build, log_path, child) = &mut running[index];
            let status = match child.try_wait() {
                Ok(status) => status,
                Err(e) => {
                    let message = format!("{}: waiting for the build: {e}", platform.name);
                    stop_builds(&mut running);
                    return Err(message);
                }
            };
            let Some(status) = status else {
                index += 1;
                continue;
            };
            let seconds = started.elapsed().as_secs_f64();
            let outcome = if !status.success() {
                Err(format!(
                    "{}: the build failed ({:?} {:?}); the end of {}:\n{}",
                    platform.name,
                    build.command.get_program(),
                    build.command.get_args().collect::<Vec<_>>(),
                    log_path.display(),
                    log_tail(log_path, 40)
                ))
            } else if !build.output.exists() {
                Err(format!("{}: {} was not built", platform.name, build.output.display()))
            } else {
                file_check::check(&build.output, platform).map(|summary| {
                    println!("build-fmu: {}: {seconds:.1} s; {summary}", platform.name);
                    Binary { platform, path: build.output.clone() }
                })
            };
            match outcome {
                Ok(binary) => binaries.push(binary),
                Err(message) => failures.push(message),
            }
            running.swap_remove(index);
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    if !failures.is_empty() {
        return Err(failures.join("\nbuild-fmu: error: "));
    }
    // The order of the platforms asked, whatever the order they finished in.
    binaries.sort_by_key(|b| targets.iter().position(|p| p.name == b.platform.name));
    Ok(binaries)
}

/// Stops the builds still running and waits for them, when build-fmu gives up early: left
/// behind, they would go on unobserved and hold their target folders' locks against the next
/// run.
fn stop_builds<P, B, L>(running: &mut Vec<(P, B, L, std::process::Child)>) {
    for (_, _, _, child) in running.iter_mut() {
        // A build that has ended already refuses the kill; the wait reaps it either way.
        let _ = child.kill();
        let _ = child.wait();
    }
    running.clear();
}

/// The last `lines` lines of the file at `path` (or why it cannot be read).
fn log_tail(path: &Path, lines: usize) -> String {
    match std::fs::read_to_string(path) {
        Ok(text) => {
            let all: Vec<&str> = text.lines().collect();
            all[all.len().saturating_sub(lines)..].join("\n")
        }
        Err(e) => format!("(cannot read it: {e})"),
    }
}

/// The binaries an FMU of FMI `version` carries: (path inside the archive, file).
fn archive_binaries(binaries: &[Binary], version: u8, id: &str) -> Vec<(String, PathBuf)> {
    binaries
        .iter()
        .filter_map(|b| b.platform.archive_path(version, id).map(|inside| (inside, b.path.clone())))
        .collect()
}

/// The committed model description at `source`, which must equal the one `generated` from
/// the code (with `update`, it is written first).
fn committed_description(source: &Path, generated: &str, update: bool) -> Result<String, String> {
    if update {
        if let Some(dir) = source.parent() {
            std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        }
        std::fs::write(source, generated).map_err(|e| format!("cannot write {}: {e}", source.display()))?;
        println!("build-fmu: wrote {}", source.display());
    }
    let committed = std::fs::read_to_string(source).map_err(|e| format!("cannot read {}: {e}", source.display()))?;
    if committed != generated {
        return Err(format!(
            "{} is out of date with the variable tables in the code (run `cargo run --release --bin build-fmu -- \
             --update-model-description` and review the diff)",
            source.display()
        ));
    }
    Ok(committed)
}

fn build_one(
    kind: ModelKind,
    root: &Path,
    native: Option<&Path>,
    binaries: &[Binary],
    out_dir: &Path,
    update: bool,
) -> Result<(), String> {
    let id = kind.info().model_identifier;
    let source = root.join("modelDescription").join(format!("{id}.xml"));
    let committed = committed_description(&source, &model_description_xml(kind, FmiVersion::Fmi2), update)?;
    let summary = xml_check::check(&committed).map_err(|e| format!("{}: {e}", source.display()))?;
    let guid = instantiation_token(kind, FmiVersion::Fmi2);
    if summary.guid != guid {
        return Err(format!("{}: guid {} differs from the binary's {guid}", source.display(), summary.guid));
    }
    if let Some(library) = native {
        binary_check::check(library, &summary.guid).map_err(|e| format!("{}: {e}", library.display()))?;
    }
    let fmu_dir = if kind.is_benchmark_floor() { out_dir.join("bench") } else { out_dir.to_path_buf() };
    let fmu = fmu_dir.join(format!("{id}.fmu"));
    let carried = archive_binaries(binaries, 2, id);
    if carried.is_empty() {
        println!("build-fmu: {id}: no FMI 2 platform among the targets, no FMI 2 FMU");
        let _ = std::fs::remove_file(&fmu);
        return Ok(());
    }
    std::fs::create_dir_all(&fmu_dir).map_err(|e| format!("cannot create {}: {e}", fmu_dir.display()))?;
    package::write_fmu(&fmu, &carried, &committed, &documentation_html(kind, FmiVersion::Fmi2))?;
    println!(
        "build-fmu: {} ({} variables, {} outputs, {} initial unknowns, GUID {guid}; {}) -> {}",
        id,
        summary.variables,
        summary.outputs,
        summary.initial_unknowns,
        folders(&carried),
        fmu.display()
    );
    Ok(())
}

fn build_one_fmi3(
    kind: ModelKind,
    root: &Path,
    native: Option<&Path>,
    binaries: &[Binary],
    out_dir: &Path,
    update: bool,
) -> Result<(), String> {
    let id = kind.info().model_identifier;
    let source = root.join("modelDescription").join("fmi3").join(format!("{id}.xml"));
    let committed = committed_description(&source, &model_description_xml(kind, FmiVersion::Fmi3), update)?;
    let summary = xml_check3::check(&committed).map_err(|e| format!("{}: {e}", source.display()))?;
    let token = instantiation_token(kind, FmiVersion::Fmi3);
    if summary.token != token {
        return Err(format!(
            "{}: instantiationToken {} differs from the binary's {token}",
            source.display(),
            summary.token
        ));
    }
    if let Some(library) = native {
        binary_check::check_fmi3(library, token).map_err(|e| format!("{}: {e}", library.display()))?;
    }
    std::fs::create_dir_all(out_dir).map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    let fmu = out_dir.join(format!("{id}.fmu"));
    let carried = archive_binaries(binaries, 3, id);
    package::write_fmu(&fmu, &carried, &committed, &documentation_html(kind, FmiVersion::Fmi3))?;
    println!(
        "build-fmu: {} FMI 3 ({} variables, {} outputs, {} states, {} event indicators, token {token}; {}) -> {}",
        id,
        summary.variables,
        summary.outputs,
        summary.states,
        summary.event_indicators,
        folders(&carried),
        fmu.display()
    );
    Ok(())
}

/// `binaries/linux64, binaries/win64` for the build log.
fn folders(carried: &[(String, PathBuf)]) -> String {
    carried
        .iter()
        .map(|(inside, _)| inside.rsplit_once('/').map_or(inside.as_str(), |(dir, _)| dir))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The interface tables of `docs/model.md`, which must be those the declarations generate
/// (with `update`, they are written first).
fn interface_tables(page: &Path, update: bool) -> Result<(), String> {
    let text = std::fs::read_to_string(page).map_err(|e| format!("cannot read {}: {e}", page.display()))?;
    let mut generated = text.clone();
    for kind in ModelKind::ALL.into_iter().filter(|k| !k.is_benchmark_floor()) {
        generated = with_interface_table(&generated, kind).ok_or_else(|| {
            format!("{}: the markers of the {} interface table are missing", page.display(), kind.info().model_name)
        })?;
    }
    if generated == text {
        return Ok(());
    }
    if !update {
        return Err(format!(
            "{}: the interface tables are out of date with the variable declarations (run `cargo run --release \
             --bin build-fmu -- --update-model-description` and review the diff)",
            page.display()
        ));
    }
    std::fs::write(page, generated).map_err(|e| format!("cannot write {}: {e}", page.display()))?;
    println!("build-fmu: wrote the interface tables of {}", page.display());
    Ok(())
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    /// A build left running when build-fmu gives up is stopped and reaped, not left behind.
    #[test]
    fn stopping_the_builds_reaps_them() {
        let child = std::process::Command::new("sleep").arg("60").spawn().expect("sleep runs");
        let pid = child.id();
        let mut running = vec![((), (), (), child)];
        super::stop_builds(&mut running);
        assert!(running.is_empty());
        // Reaped: no process of that id is left, not even a zombie.
        assert!(!std::path::Path::new(&format!("/proc/{pid}")).exists(), "process {pid} is still there");
    }
}
