//! `cargo run --release --bin build-fmu`: builds the FMU binary and packages
//! `target/fmu/<ModelIdentifier>.fmu` for every model in the crate.
//!
//! Steps, each of which stops the build with a clear message when it fails:
//! 1. `cargo build --release --lib` (the cdylib);
//! 2. compare `modelDescription/<id>.xml` with what the binary's variable tables generate
//!    (`--update-model-description` rewrites them);
//! 3. check the XML with quick-xml: well-formed, unique names and value references,
//!    ModelStructure indices valid and complete, units defined;
//! 4. load the built library with `dlopen` and check that it accepts the XML's GUID (and
//!    refuses another), and that it exports every FMI 2.0 function;
//! 5. zip `modelDescription.xml`, `binaries/linux64/<id>.so` and `documentation/index.html`;
//! 6. check `modelDescription/StewartSystem.ssd` (the closed loop) against the models and zip
//!    it with both FMUs into `target/fmu/StewartSystem.ssp`.

mod binary_check;
mod package;
mod ssd_check;
mod xml_check;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use stewart_fmu::models::ModelKind;
use stewart_fmu::models::model_description::{documentation_html, instantiation_token, model_description_xml};

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

    let ssd_path = root.join("modelDescription").join("StewartSystem.ssd");
    let ssd = std::fs::read_to_string(&ssd_path).map_err(|e| format!("cannot read {}: {e}", ssd_path.display()))?;
    let sources = ssd_check::check(&ssd).map_err(|e| format!("{}: {e}", ssd_path.display()))?;
    let fmus: Vec<PathBuf> = sources.iter().map(|s| out_dir.join(s)).collect();
    let fmu_refs: Vec<&Path> = fmus.iter().map(|p| p.as_path()).collect();
    let ssp = out_dir.join("StewartSystem.ssp");
    package::write_ssp(&ssp, &ssd, &fmu_refs)?;
    println!("build-fmu: StewartSystem ({} components) -> {}", fmus.len(), ssp.display());
    Ok(())
}

fn build_one(kind: ModelKind, root: &Path, library: &Path, out_dir: &Path, update: bool) -> Result<(), String> {
    let id = kind.info().model_identifier;
    let source = root.join("modelDescription").join(format!("{id}.xml"));
    let generated = model_description_xml(kind);
    if update {
        std::fs::write(&source, &generated).map_err(|e| format!("cannot write {}: {e}", source.display()))?;
        println!("build-fmu: wrote {}", source.display());
    }
    let committed = std::fs::read_to_string(&source).map_err(|e| format!("cannot read {}: {e}", source.display()))?;
    if committed != generated {
        return Err(format!(
            "{} is out of date with the variable tables in the code (run `cargo run --release --bin build-fmu -- \
             --update-model-description` and review the diff)",
            source.display()
        ));
    }
    let summary = xml_check::check(&committed).map_err(|e| format!("{}: {e}", source.display()))?;
    let guid = instantiation_token(kind);
    if summary.guid != guid {
        return Err(format!("{}: guid {} differs from the binary's {guid}", source.display(), summary.guid));
    }
    binary_check::check(library, &summary.guid).map_err(|e| format!("{}: {e}", library.display()))?;
    let fmu_dir = if kind.is_benchmark_floor() { out_dir.join("bench") } else { out_dir.to_path_buf() };
    std::fs::create_dir_all(&fmu_dir).map_err(|e| format!("cannot create {}: {e}", fmu_dir.display()))?;
    let fmu = fmu_dir.join(format!("{id}.fmu"));
    package::write_fmu(&fmu, id, &committed, library, &documentation_html(kind))?;
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
