//! Reading compiled artifacts: the JSON files. (The reasoner's examples
//! are built from the demonstrations themselves, by the run-time's own
//! graph encoder: `teach`; `graphs.safetensors` is for other tools.)

use crate::error::{PipelineError, Result};
use std::path::Path;

/// A compiled JSON artifact at `path`.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let bytes = std::fs::read(path).map_err(|e| PipelineError::Read {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    serde_json::from_slice(&bytes).map_err(|e| PipelineError::Artifact {
        file: path.display().to_string(),
        problem: format!("not a packwright artifact ({e})"),
    })
}
