//! The one per-joint rule: a parameter is one number for every joint, or a
//! list with exactly one value per joint, in the model's joint order.

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};

use crate::error::Invalid;

/// A per-joint parameter. In TOML either `0.5` or `[0.5, 0.5, 0.4, 0.4, 0.3, 0.2, 0.2]`.
#[derive(Clone, Debug, PartialEq)]
pub enum PerJoint {
    /// the same value for every joint
    All(f64),
    /// one value per joint, in the model's joint order
    Each(Vec<f64>),
}

impl PerJoint {
    /// One value per joint for an `n`-joint model, each finite and ≥ 0;
    /// `key` (`dynamics.gain`) names the parameter in errors.
    pub fn resolve(&self, n: usize, key: &str) -> Result<Vec<f64>, Invalid> {
        let v = match self {
            PerJoint::All(x) => vec![*x; n],
            PerJoint::Each(v) if v.len() == n => v.clone(),
            PerJoint::Each(v) => {
                return Err(Invalid::new(
                    key,
                    format!(
                        "has {} values, the robot has {n} joints (give one number for all joints, or one per joint)",
                        v.len()
                    ),
                ))
            }
        };
        match v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            Some(i) => Err(Invalid::new(
                key,
                format!("joint {i}: {} is not a finite non-negative number", v[i]),
            )),
            None => Ok(v),
        }
    }

    /// Every value finite and ≥ 0 (the count is checked against a model by [`PerJoint::resolve`]).
    pub fn check(&self, key: &str) -> Result<(), Invalid> {
        let values: &[f64] = match self {
            PerJoint::All(x) => std::slice::from_ref(x),
            PerJoint::Each(v) => v,
        };
        if values.is_empty() {
            return Err(Invalid::new(key, "empty list"));
        }
        match values.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
            Some(x) => Err(Invalid::new(
                key,
                format!("{x} is not a finite non-negative number"),
            )),
            None => Ok(()),
        }
    }
}

impl Serialize for PerJoint {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            PerJoint::All(x) => s.serialize_f64(*x),
            PerJoint::Each(v) => v.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for PerJoint {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<PerJoint, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = PerJoint;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array of numbers (one per joint)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<PerJoint, E> {
                Ok(PerJoint::All(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<PerJoint, E> {
                Ok(PerJoint::All(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<PerJoint, E> {
                Ok(PerJoint::All(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<PerJoint, A::Error> {
                let mut v = Vec::with_capacity(seq.size_hint().unwrap_or(7).min(64));
                while let Some(x) = seq.next_element::<f64>()? {
                    v.push(x);
                }
                Ok(PerJoint::Each(v))
            }
        }
        deserializer.deserialize_any(V)
    }
}
