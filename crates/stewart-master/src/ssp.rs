//! An `.ssp` archive: its `SystemStructure.ssd` and the FMUs it names under `resources/`,
//! opened into a `System`.

use std::path::Path;
use std::sync::Arc;

use crate::fmu::{Fmu, read_from_zip};
use crate::ssd::SystemDescription;
use crate::system::System;

/// The system an SSP file describes, each component's FMU unpacked from the archive (an FMU
/// used by several components is unpacked once).
pub fn open(path: &Path) -> Result<(System, SystemDescription), String> {
    let label = path.display().to_string();
    let data = std::fs::read(path).map_err(|e| format!("cannot read the SSP {label}: {e}"))?;
    let text = read_from_zip(&data, "SystemStructure.ssd", &label)?;
    let text = String::from_utf8(text).map_err(|_| format!("{label}: SystemStructure.ssd is not UTF-8"))?;
    let description = SystemDescription::parse(&text).map_err(|e| format!("{label}: {e}"))?;
    let mut unpacked: Vec<(String, Arc<Fmu>)> = vec![];
    let mut fmus = vec![];
    for c in &description.components {
        let fmu = match unpacked.iter().find(|(s, _)| s == &c.source) {
            Some((_, f)) => f.clone(),
            None => {
                let bytes = read_from_zip(&data, &c.source, &label)?;
                let fmu = Arc::new(Fmu::from_bytes(&bytes, &format!("{label}:{}", c.source))?);
                unpacked.push((c.source.clone(), fmu.clone()));
                fmu
            }
        };
        fmus.push((c.name.clone(), fmu));
    }
    let system = System::new(fmus, Some(&description)).map_err(|e| format!("{label}: {e}"))?;
    Ok((system, description))
}
