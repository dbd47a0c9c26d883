//! The committed `modelDescription/*.xml` (FMI 2) and `modelDescription/fmi3/*.xml` (FMI 3)
//! files are exactly what the binary's variable tables generate, every dependency in the
//! tables names a variable that exists, and each token selects its own model.

use std::path::Path;
use stewart_fmu::fmi::FmiVersion;
use stewart_fmu::fmi::description::{
    documentation_html, instantiation_token, interface_markdown, model_description_xml, model_of_token,
    with_interface_table,
};
use stewart_fmu::models::ModelKind;
use stewart_fmu::models::variables::Dependency;

use crate::common::repository;

fn committed(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn committed_model_descriptions_match_the_code() {
    for kind in ModelKind::ALL {
        let id = kind.info().model_identifier;
        let folder = repository().join("modelDescription");
        let mut versions = vec![(FmiVersion::Fmi2, folder.join(format!("{id}.xml")))];
        if !kind.is_benchmark_floor() {
            versions.push((FmiVersion::Fmi3, folder.join("fmi3").join(format!("{id}.xml"))));
        }
        for (version, path) in versions {
            let text = committed(&path);
            assert!(
                text == model_description_xml(kind, version),
                "{} is out of date: run `cargo run --release --bin build-fmu -- --update-model-description`",
                path.display()
            );
            let token = instantiation_token(kind, version);
            assert!(text.contains(token));
            assert_eq!(model_of_token(token, version), Some(kind));
            let other = if version == FmiVersion::Fmi2 { FmiVersion::Fmi3 } else { FmiVersion::Fmi2 };
            assert_eq!(model_of_token(token, other), None, "a token belongs to one FMI version");
            let html = documentation_html(kind, version);
            assert!(html.contains("<table>") && html.contains(id));
        }
    }
}

/// `docs/model.md`'s interface tables are what the declarations generate.
#[test]
fn the_interface_tables_of_the_documentation_match_the_code() {
    let path = repository().join("docs").join("model.md");
    let text = committed(&path);
    for kind in ModelKind::ALL.into_iter().filter(|k| !k.is_benchmark_floor()) {
        let generated = with_interface_table(&text, kind).expect("the table's markers");
        assert!(
            generated == text,
            "{}: the {} table is out of date: run `cargo run --release --bin build-fmu -- \
             --update-model-description`",
            path.display(),
            kind.info().model_name
        );
        assert!(text.contains(&interface_markdown(kind)));
    }
}

#[test]
fn every_dependency_names_an_existing_variable() {
    for kind in ModelKind::ALL {
        let groups = kind.info().groups;
        for g in groups {
            for deps in [g.output_dependencies, g.initial_dependencies, g.derivative_dependencies] {
                Dependency::each_known(deps, &mut |known, same| {
                    let target = groups.get(known);
                    assert!(
                        target.is_some(),
                        "{}: {} depends on a variable that does not exist",
                        kind.info().model_name,
                        g.name
                    );
                    if let (true, Some(t)) = (same, target) {
                        assert_eq!(
                            t.len(),
                            g.len(),
                            "{}: {} depends element-wise on {} of another size",
                            kind.info().model_name,
                            g.name,
                            t.name
                        );
                    }
                });
            }
            if let Some(state) = g.derivative_of {
                assert!(groups.iter().any(|t| t.name == state), "{}: derivative of unknown {state}", g.name);
            }
        }
        for (state, element) in kind.info().states {
            let g =
                groups.iter().find(|g| g.name == *state).unwrap_or_else(|| panic!("state {state} is not a variable"));
            assert!(*element < g.len());
        }
    }
}
