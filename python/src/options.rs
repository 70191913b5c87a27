//! Sampler options from Python keyword arguments: the fields of
//! `brdf_sampling::SetOptions` (with its tree's split parameters flattened: `n_max`,
//! `max_depth`, `min_leaf_size`, `volume_tolerance`) and of `baselines::BaselineOptions`
//! (prefixed by family: `lobe_*`, `cdf_*`, `factored_*`, `srbf_*`). Unknown keys and values
//! out of range are `ValueError`s with the library's message.

use baselines::BaselineOptions;
use brdf_sampling::SetOptions;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;

use crate::errors::{invalid, value_error};

/// The split parameters of `SetOptions::tree` accepted at the top level.
const TREE_KEYS: [&str; 4] = ["n_max", "max_depth", "min_leaf_size", "volume_tolerance"];

/// Fields of the adaptive-set options that are not user options (set by the variant).
const SET_HIDDEN: [&str; 1] = ["tree"];

/// Assigns one `BaselineOptions` field from a Python value; `false` if `key` is not one.
fn set_baseline(b: &mut BaselineOptions, key: &str, v: &Bound<'_, PyAny>) -> PyResult<bool> {
    macro_rules! fields {
        ($($name:literal => $($field:ident).+),* $(,)?) => {
            match key {
                $($name => { b.$($field).+ = v.extract().map_err(|e| {
                    invalid(format!("option {key}: {e}"))
                })?; Ok(true) })*
                _ => Ok(false),
            }
        };
    }
    fields! {
        "lobe_exponent" => lobe.exponent,
        "lobe_slices" => lobe.slices,
        "lobe_phi_slices" => lobe.phi_slices,
        "lobe_min_exponent" => lobe.min_exponent,
        "lobe_max_exponent" => lobe.max_exponent,
        "lobe_min_defensive" => lobe.min_defensive,
        "cdf_slices" => cdf.slices,
        "cdf_anisotropic_slices" => cdf.anisotropic_slices,
        "cdf_n_z" => cdf.n_z,
        "cdf_n_phi" => cdf.n_phi,
        "cdf_supersampling" => cdf.supersampling,
        "cdf_epsilon" => cdf.epsilon,
        "cdf_floor" => cdf.floor,
        "factored_theta_o_cells" => factored.theta_o_cells,
        "factored_phi_o_cells" => factored.phi_o_cells,
        "factored_theta_p_cells" => factored.theta_p_cells,
        "factored_phi_p_cells" => factored.phi_p_cells,
        "factored_outer_terms" => factored.outer_terms,
        "factored_inner_terms" => factored.inner_terms,
        "factored_max_iterations" => factored.max_iterations,
        "factored_tolerance" => factored.tolerance,
        "factored_seed" => factored.seed,
        "factored_defensive_alpha" => factored.defensive_alpha,
        "factored_isotropic_rows" => factored.isotropic_rows,
        "srbf_slices" => srbf.slices,
        "srbf_phi_slices" => srbf.phi_slices,
        "srbf_brdf_lobes" => srbf.brdf_lobes,
        "srbf_fit_rows" => srbf.fit_rows,
        "srbf_brdf_defensive" => srbf.brdf_defensive,
        "srbf_map_lobes" => srbf.map_lobes,
        "srbf_max_iter" => srbf.max_iter,
        "srbf_product_lobes" => srbf.product_lobes,
        "srbf_defensive" => srbf.defensive,
    }
}

/// The baseline option names (for error messages and `option_names()`).
pub(crate) const BASELINE_KEYS: [&str; 33] = [
    "lobe_exponent",
    "lobe_slices",
    "lobe_phi_slices",
    "lobe_min_exponent",
    "lobe_max_exponent",
    "lobe_min_defensive",
    "cdf_slices",
    "cdf_anisotropic_slices",
    "cdf_n_z",
    "cdf_n_phi",
    "cdf_supersampling",
    "cdf_epsilon",
    "cdf_floor",
    "factored_theta_o_cells",
    "factored_phi_o_cells",
    "factored_theta_p_cells",
    "factored_phi_p_cells",
    "factored_outer_terms",
    "factored_inner_terms",
    "factored_max_iterations",
    "factored_tolerance",
    "factored_seed",
    "factored_defensive_alpha",
    "factored_isotropic_rows",
    "srbf_slices",
    "srbf_phi_slices",
    "srbf_brdf_lobes",
    "srbf_fit_rows",
    "srbf_brdf_defensive",
    "srbf_map_lobes",
    "srbf_max_iter",
    "srbf_product_lobes",
    "srbf_defensive",
];

/// The adaptive-set option names (`SetOptions` fields and the flattened tree keys).
pub(crate) fn set_keys() -> Vec<String> {
    let mut keys: Vec<String> = match serde_json::to_value(SetOptions::default()) {
        Ok(Value::Object(m)) => m
            .keys()
            .filter(|k| !SET_HIDDEN.contains(&k.as_str()))
            .cloned()
            .collect(),
        _ => Vec::new(),
    };
    keys.extend(TREE_KEYS.iter().map(|s| s.to_string()));
    keys.sort();
    keys
}

/// A Python value as JSON (bool, int, float, str, None, list/tuple of those).
fn to_json(v: &Bound<'_, PyAny>) -> PyResult<Value> {
    if v.is_none() {
        Ok(Value::Null)
    } else if v.is_instance_of::<PyBool>() {
        Ok(Value::Bool(v.extract()?))
    } else if v.is_instance_of::<PyInt>() {
        let i: i64 = v.extract()?;
        Ok(Value::from(i))
    } else if v.is_instance_of::<PyFloat>() {
        let x: f64 = v.extract()?;
        serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| invalid(format!("{x} is not a finite number")))
    } else if v.is_instance_of::<PyString>() {
        Ok(Value::String(v.extract()?))
    } else if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = v.extract()?;
        Ok(Value::Array(
            items.iter().map(to_json).collect::<PyResult<_>>()?,
        ))
    } else {
        // numpy scalars and the like
        if let Ok(x) = v.extract::<f64>() {
            return to_json(&PyFloat::new(v.py(), x).into_any());
        }
        Err(invalid(format!(
            "unsupported option value {}",
            v.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        )))
    }
}

/// Both option families from keyword arguments, checked.
pub(crate) fn direction_options(
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<(SetOptions, BaselineOptions)> {
    let mut baselines = BaselineOptions::default();
    let mut set = serde_json::to_value(SetOptions::default())
        .map_err(|e| invalid(format!("internal: {e}")))?;
    if let Some(kwargs) = kwargs {
        for (k, v) in kwargs.iter() {
            let key: String = k.extract()?;
            if set_baseline(&mut baselines, &key, &v)? {
                continue;
            }
            let value = to_json(&v).map_err(|e| invalid(format!("option {key}: {e}")))?;
            let obj = set
                .as_object_mut()
                .expect("SetOptions serialises to an object");
            if TREE_KEYS.contains(&key.as_str()) {
                obj["tree"][key.as_str()] = value;
            } else if obj.contains_key(&key) && !SET_HIDDEN.contains(&key.as_str()) {
                obj[key.as_str()] = value;
            } else {
                return Err(invalid(format!(
                    "unknown option `{key}`; valid: {}, {}",
                    set_keys().join(", "),
                    BASELINE_KEYS.join(", ")
                )));
            }
        }
    }
    let set: SetOptions =
        serde_json::from_value(set).map_err(|e| invalid(format!("bad option value: {e}")))?;
    set.validate().map_err(|e| value_error(&e))?;
    baselines.lobe.validate().map_err(|e| value_error(&e))?;
    baselines.cdf.validate().map_err(|e| value_error(&e))?;
    baselines.factored.validate().map_err(|e| value_error(&e))?;
    baselines.srbf.validate().map_err(|e| value_error(&e))?;
    Ok((set, baselines))
}
