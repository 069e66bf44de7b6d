//! Reading `{"samples": [...]}` input with messages that name the sample and the field.

use super::CliError;
use serde_json::Value;

pub struct Samples {
    pub samples: Vec<Value>,
}

impl Samples {
    pub fn parse(text: &str) -> Result<Self, CliError> {
        let root: Value = serde_json::from_str(text)
            .map_err(|e| CliError(format!("the input is not valid JSON: {e}")))?;
        let Some(samples) = root.get("samples") else {
            return Err(CliError(
                "the input has no field `samples` (expected {\"samples\": [...]})".into(),
            ));
        };
        let Some(samples) = samples.as_array() else {
            return Err(CliError(
                "the input's field `samples` must be an array".into(),
            ));
        };
        Ok(Samples {
            samples: samples.clone(),
        })
    }
}

/// Field `name` of sample `index` as a vector of exactly `len` finite numbers.
pub fn vector(sample: &Value, index: usize, name: &str, len: usize) -> Result<Vec<f64>, CliError> {
    let Some(field) = sample.get(name) else {
        return Err(CliError(format!("sample {index}: missing field `{name}`")));
    };
    let Some(items) = field.as_array() else {
        return Err(CliError(format!(
            "sample {index}: field `{name}` must be an array of numbers"
        )));
    };
    if items.len() != len {
        return Err(CliError(format!(
            "sample {index}: field `{name}` has {} entries, the model needs {len}",
            items.len()
        )));
    }
    items
        .iter()
        .enumerate()
        .map(|(k, x)| {
            x.as_f64().filter(|v| v.is_finite()).ok_or_else(|| {
                CliError(format!(
                    "sample {index}: field `{name}`[{k}] is not a finite number: {x}"
                ))
            })
        })
        .collect()
}
