//! The outputs of `calibrate`: `parameters.csv`, `residuals.csv` and `evaluations.csv`
//! (`fitted.toml` is the study's own `config.toml` form).

use super::{csv_bytes, num, opt};

/// One row of `residuals.csv`: an observed figure against the model's.
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualRow {
    /// Mode, 1-based.
    pub mode: usize,
    /// Exposure, ms.
    pub exposure_ms: f64,
    /// The quantity's name (`mu_a`, `chi_mu`, ...).
    pub quantity: &'static str,
    /// The observed value.
    pub observed: f64,
    /// Its stated standard uncertainty, if any.
    pub u_observed: Option<f64>,
    /// The model's value.
    pub model: f64,
    /// The model's standard uncertainty (Monte Carlo).
    pub u_model: f64,
    /// The normalised residual.
    pub residual: f64,
}

/// `residuals.csv`: `mode,exposure_ms,quantity,observed,u_observed,model,u_model,residual`
/// (non-finite model figures as empty cells).
pub fn residuals_csv(rows: &[ResidualRow]) -> Vec<u8> {
    csv_bytes(
        "mode,exposure_ms,quantity,observed,u_observed,model,u_model,residual",
        rows,
        |r| {
            [
                r.mode.to_string(),
                r.exposure_ms.to_string(),
                r.quantity.to_string(),
                r.observed.to_string(),
                opt(r.u_observed),
                num(r.model),
                num(r.u_model),
                num(r.residual),
            ]
        },
    )
}

/// `evaluations.csv`: one column per free parameter (`names`), then `chi2,objective`; one row
/// per evaluation `(values, chi2, objective)`.
pub fn evaluations_csv<'a>(
    names: &[&str],
    rows: impl IntoIterator<Item = (&'a [f64], f64, f64)>,
) -> Vec<u8> {
    let mut s: String = names.iter().map(|n| format!("{n},")).collect();
    s += "chi2,objective\n";
    for (x, chi2, objective) in rows {
        for v in x {
            s += &format!("{v},");
        }
        s += &format!("{chi2},{objective}\n");
    }
    s.into_bytes()
}

/// One row of `parameters.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterRow {
    /// The knob's name.
    pub name: &'static str,
    /// The fitted value.
    pub value: f64,
    /// Its standard uncertainty, when the fit gives one.
    pub u: Option<f64>,
    /// The search range.
    pub range: (f64, f64),
}

/// `parameters.csv`: `name,value,u,lo,hi`.
pub fn parameters_csv(rows: &[ParameterRow]) -> Vec<u8> {
    csv_bytes("name,value,u,lo,hi", rows, |r| {
        [
            r.name.to_string(),
            r.value.to_string(),
            opt(r.u),
            r.range.0.to_string(),
            r.range.1.to_string(),
        ]
    })
}
