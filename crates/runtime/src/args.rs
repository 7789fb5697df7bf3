//! Minimal `--flag value` parsing for the service binaries.

/// A command line that cannot be parsed: names the flag.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ArgsError {
    #[error("{0} needs a value")]
    MissingValue(String),
    #[error("unknown argument '{0}'")]
    Unknown(String),
    #[error("{flag}: cannot parse '{value}'")]
    Value { flag: String, value: String },
    #[error("{0} is required")]
    Required(String),
}

/// Flags after the program name, each `--name value` (or a bare `--name` switch).
#[derive(Debug, Default)]
pub struct Args {
    pairs: Vec<(String, Option<String>)>,
}

impl Args {
    /// Parse `args`; `switches` take no value, `valued` take one (and may repeat).
    pub fn parse(
        args: impl IntoIterator<Item = String>,
        valued: &[&str],
        switches: &[&str],
    ) -> Result<Args, ArgsError> {
        let mut pairs = Vec::new();
        let mut it = args.into_iter();
        while let Some(a) = it.next() {
            if switches.contains(&a.as_str()) {
                pairs.push((a, None));
            } else if valued.contains(&a.as_str()) {
                let v = it
                    .next()
                    .ok_or_else(|| ArgsError::MissingValue(a.clone()))?;
                pairs.push((a, Some(v)));
            } else {
                return Err(ArgsError::Unknown(a));
            }
        }
        Ok(Args { pairs })
    }

    /// Last value of `name`.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.pairs
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .and_then(|(_, v)| v.as_deref())
    }

    /// Every value of a repeatable flag, in order.
    pub fn all(&self, name: &str) -> Vec<&str> {
        self.pairs
            .iter()
            .filter(|(n, _)| n == name)
            .filter_map(|(_, v)| v.as_deref())
            .collect()
    }

    pub fn has(&self, name: &str) -> bool {
        self.pairs.iter().any(|(n, _)| n == name)
    }

    /// `name` parsed as `T`, with an error naming the flag.
    pub fn parse_value<T: std::str::FromStr>(&self, name: &str) -> Result<Option<T>, ArgsError> {
        match self.get(name) {
            None => Ok(None),
            Some(v) => v.parse::<T>().map(Some).map_err(|_| ArgsError::Value {
                flag: name.to_string(),
                value: v.to_string(),
            }),
        }
    }

    /// A required flag parsed as `T`.
    pub fn require<T: std::str::FromStr>(&self, name: &str) -> Result<T, ArgsError> {
        self.parse_value(name)?
            .ok_or_else(|| ArgsError::Required(name.to_string()))
    }
}
