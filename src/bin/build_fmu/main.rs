//! `cargo run --release --bin build-fmu`: builds the FMU binary and packages
//! `target/fmu/<ModelIdentifier>.fmu` (FMI 2.0) for every model in the crate and
//! `target/fmu/fmi3/<ModelIdentifier>.fmu` (FMI 3.0) for the product models, from the same
//! binary.
//!
//! Steps, each of which stops the build with a clear message when it fails:
//! 1. `cargo build --release --lib` (the cdylib);
//! 2. compare `modelDescription/<id>.xml` and `modelDescription/fmi3/<id>.xml` with what the
//!    binary's variable tables generate (`--update-model-description` rewrites them);
//! 3. check the XML with quick-xml: well-formed, unique names and value references,
//!    ModelStructure valid and complete, units defined, start values sized;
//! 4. load the built library with `dlopen` and check that it accepts the XML's GUID or token
//!    (and refuses another), and that it exports every FMI 2.0 and FMI 3.0 function;
//! 5. zip `modelDescription.xml`, the binary (`binaries/linux64/<id>.so`, FMI 3
//!    `binaries/x86_64-linux/<id>.so`) and `documentation/index.html`;
//! 6. check `modelDescription/StewartSystem.ssd` (the closed loop) and
//!    `StewartSystemDrives.ssd` (with electric drives) against the models and zip each with
//!    both FMI 2 FMUs into `target/fmu/StewartSystem.ssp`, `StewartSystemDrives.ssp`.

mod binary_check;
mod package;
mod ssd_check;
mod xml_check;
mod xml_check3;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use stewart_fmu::fmi::FmiVersion;
use stewart_fmu::fmi::description::{
    documentation_html, instantiation_token, model_description_xml, with_interface_table,
};
use stewart_fmu::models::ModelKind;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("build-fmu: error: {message}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let update = args.iter().any(|a| a == "--update-model-description");
    if let Some(other) = args.iter().find(|a| *a != "--update-model-description") {
        return Err(format!("unknown argument {other} (usage: build-fmu [--update-model-description])"));
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));

    println!("build-fmu: building the FMU binary (cargo build --release --lib)");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args(["build", "--release", "--lib"])
        .current_dir(&root)
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err("cargo build --release --lib failed".into());
    }
    let target_dir = std::env::var("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|_| root.join("target"));
    let library = target_dir.join("release").join("libstewart_fmu.so");
    if !library.exists() {
        return Err(format!("{} was not built", library.display()));
    }

    let out_dir = target_dir.join("fmu");
    std::fs::create_dir_all(&out_dir).map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    for kind in ModelKind::ALL {
        build_one(kind, &root, &library, &out_dir, update)?;
    }
    for kind in ModelKind::ALL.into_iter().filter(|k| !k.is_benchmark_floor()) {
        build_one_fmi3(kind, &root, &library, &out_dir.join("fmi3"), update)?;
    }

    interface_tables(&root.join("docs").join("model.md"), update)?;

    // The closed loop with force commands, and with electric drives (voltage commands).
    for system in ["StewartSystem", "StewartSystemDrives"] {
        let ssd_path = root.join("modelDescription").join(format!("{system}.ssd"));
        let ssd = std::fs::read_to_string(&ssd_path).map_err(|e| format!("cannot read {}: {e}", ssd_path.display()))?;
        let sources = ssd_check::check(&ssd).map_err(|e| format!("{}: {e}", ssd_path.display()))?;
        let fmus: Vec<PathBuf> = sources.iter().map(|s| out_dir.join(s)).collect();
        let fmu_refs: Vec<&Path> = fmus.iter().map(|p| p.as_path()).collect();
        let ssp = out_dir.join(format!("{system}.ssp"));
        package::write_ssp(&ssp, &ssd, &fmu_refs)?;
        println!("build-fmu: {system} ({} components) -> {}", fmus.len(), ssp.display());
    }
    Ok(())
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

fn build_one(kind: ModelKind, root: &Path, library: &Path, out_dir: &Path, update: bool) -> Result<(), String> {
    let id = kind.info().model_identifier;
    let source = root.join("modelDescription").join(format!("{id}.xml"));
    let committed = committed_description(&source, &model_description_xml(kind, FmiVersion::Fmi2), update)?;
    let summary = xml_check::check(&committed).map_err(|e| format!("{}: {e}", source.display()))?;
    let guid = instantiation_token(kind, FmiVersion::Fmi2);
    if summary.guid != guid {
        return Err(format!("{}: guid {} differs from the binary's {guid}", source.display(), summary.guid));
    }
    binary_check::check(library, &summary.guid).map_err(|e| format!("{}: {e}", library.display()))?;
    let fmu_dir = if kind.is_benchmark_floor() { out_dir.join("bench") } else { out_dir.to_path_buf() };
    std::fs::create_dir_all(&fmu_dir).map_err(|e| format!("cannot create {}: {e}", fmu_dir.display()))?;
    let fmu = fmu_dir.join(format!("{id}.fmu"));
    let binary = format!("binaries/linux64/{id}.so");
    package::write_fmu(&fmu, &binary, &committed, library, &documentation_html(kind, FmiVersion::Fmi2))?;
    println!(
        "build-fmu: {} ({} variables, {} outputs, {} initial unknowns, GUID {guid}) -> {}",
        id,
        summary.variables,
        summary.outputs,
        summary.initial_unknowns,
        fmu.display()
    );
    Ok(())
}

fn build_one_fmi3(kind: ModelKind, root: &Path, library: &Path, out_dir: &Path, update: bool) -> Result<(), String> {
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
    binary_check::check_fmi3(library, token).map_err(|e| format!("{}: {e}", library.display()))?;
    std::fs::create_dir_all(out_dir).map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    let fmu = out_dir.join(format!("{id}.fmu"));
    let binary = format!("binaries/x86_64-linux/{id}.so");
    package::write_fmu(&fmu, &binary, &committed, library, &documentation_html(kind, FmiVersion::Fmi3))?;
    println!(
        "build-fmu: {} FMI 3 ({} variables, {} outputs, {} states, {} event indicators, token {token}) -> {}",
        id,
        summary.variables,
        summary.outputs,
        summary.states,
        summary.event_indicators,
        fmu.display()
    );
    Ok(())
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
