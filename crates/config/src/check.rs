//! Range checks shared by the sections' `validate`, each naming the key.

use crate::error::Invalid;

/// `section.key` for errors.
pub(crate) fn key(section: &str, name: &str) -> String {
    format!("{section}.{name}")
}

/// finite and > 0
pub(crate) fn positive(section: &str, name: &str, v: f64) -> Result<(), Invalid> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Invalid::new(
            key(section, name),
            format!("{v} is not a positive number"),
        ))
    }
}

/// finite and ≥ 0
pub(crate) fn non_negative(section: &str, name: &str, v: f64) -> Result<(), Invalid> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Invalid::new(
            key(section, name),
            format!("{v} is not a finite non-negative number"),
        ))
    }
}

/// finite and in `[lo, hi]`
pub(crate) fn within(section: &str, name: &str, v: f64, lo: f64, hi: f64) -> Result<(), Invalid> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(Invalid::new(
            key(section, name),
            format!("{v} is not in [{lo}, {hi}]"),
        ))
    }
}

/// every component finite
pub(crate) fn finite(section: &str, name: &str, v: &[f64]) -> Result<(), Invalid> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(Invalid::new(
            key(section, name),
            format!("{x} is not a finite number"),
        )),
        None => Ok(()),
    }
}
