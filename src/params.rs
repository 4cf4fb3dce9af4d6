//! Tracer and acceleration-structure parameters: a name → value map from the experiment's
//! parameter grid, read through typed getters that reject unknown keys and bad values.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use crate::error::{Error, Result};

#[derive(Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Params(pub BTreeMap<String, String>);

impl Params {
    pub fn new() -> Self {
        Params::default()
    }

    pub fn with(mut self, key: &str, value: impl ToString) -> Self {
        self.0.insert(key.to_string(), value.to_string());
        self
    }

    /// The value of `key` parsed as `T`, or `default` when absent.
    pub fn get_or<T: FromStr>(&self, key: &str, default: T) -> Result<T> {
        match self.0.get(key) {
            None => Ok(default),
            Some(v) => v
                .parse()
                .map_err(|_| Error::usage(format!("parameter {key} = {v:?} is not a valid value"))),
        }
    }

    /// Only the entries whose key is in `keys` (what one tracer or structure reads).
    pub fn subset(&self, keys: &[&str]) -> Params {
        Params(
            self.0
                .iter()
                .filter(|(k, _)| keys.contains(&k.as_str()))
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect(),
        )
    }

    /// Fails on the first key not in `allowed`, naming who rejected it.
    pub fn check_known(&self, who: &str, allowed: &[&str]) -> Result<()> {
        match self.0.keys().find(|k| !allowed.contains(&k.as_str())) {
            None => Ok(()),
            Some(k) => Err(Error::usage(format!(
                "unknown parameter {k:?} for {who} (known: {})",
                allowed.join(", ")
            ))),
        }
    }
}

/// The keys `first` then `then`, at compile time: one list of keys made of two others, so
/// neither is copied by hand (`N` must be their total length).
pub const fn concat_keys<const N: usize>(
    first: &[&'static str],
    then: &[&'static str],
) -> [&'static str; N] {
    assert!(first.len() + then.len() == N, "N is the total length");
    let mut keys = [""; N];
    let mut i = 0;
    while i < N {
        keys[i] = match i < first.len() {
            true => first[i],
            false => then[i - first.len()],
        };
        i += 1;
    }
    keys
}

impl fmt::Display for Params {
    /// `key=value;key=value`, sorted: the `parameters` column of runs.csv.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self.0.iter().map(|(k, v)| format!("{k}={v}")).collect();
        f.write_str(&parts.join(";"))
    }
}
