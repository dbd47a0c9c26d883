//! The committed `modelDescription/*.xml` files are exactly what the binary's variable tables
//! generate: the XML a host reads and the code it runs cannot disagree.

use stewart_fmu::models::ModelKind;
use stewart_fmu::models::model_description::{documentation_html, instantiation_token, model_description_xml};

#[test]
fn committed_model_descriptions_match_the_code() {
    for kind in ModelKind::ALL {
        let id = kind.info().model_identifier;
        let path = format!("{}/modelDescription/{id}.xml", env!("CARGO_MANIFEST_DIR"));
        let committed = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        assert!(
            committed == model_description_xml(kind),
            "{path} is out of date: run `cargo run --release --bin build-fmu -- --update-model-description`"
        );
        assert!(committed.contains(&instantiation_token(kind)));
        assert_eq!(ModelKind::from_guid(&instantiation_token(kind)), Some(kind));
        let html = documentation_html(kind);
        assert!(html.contains("<table>") && html.contains(id));
    }
}
