//! Parameters as the host sees them: owned descriptors read from a plugin's header, and
//! values parsed from `key=value,key=value` text (`--algo NAME:key=value,...`) and checked
//! against them.

use std::fmt;

/// The type of a parameter, with a choice's names.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "lowercase", tag = "type", content = "choices")]
pub enum ParamKind {
    Float,
    Int,
    Bool,
    Choice(Vec<String>),
}

/// One parameter of a loaded plugin.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ParamInfo {
    pub name: String,
    pub help: String,
    #[serde(flatten)]
    pub kind: ParamKind,
    /// Inclusive range and default (a choice's index, 0/1 for a bool).
    pub min: f64,
    pub max: f64,
    pub default: f64,
}

impl ParamInfo {
    /// A value as text: a choice's name, `true`/`false`, or the number.
    pub fn format_value(&self, v: f64) -> String {
        match &self.kind {
            ParamKind::Choice(names) => names
                .get(v.max(0.0) as usize)
                .cloned()
                .unwrap_or_else(|| v.to_string()),
            ParamKind::Bool => (v != 0.0).to_string(),
            _ => v.to_string(),
        }
    }

    /// `float in 0..=1`, `int in 3..=15`, `bool`, `one of fast|default|high`.
    pub fn describe_type(&self) -> String {
        match &self.kind {
            ParamKind::Float => format!("float in {}..={}", self.min, self.max),
            ParamKind::Int => format!("int in {}..={}", self.min, self.max),
            ParamKind::Bool => "bool".to_string(),
            ParamKind::Choice(names) => format!("one of {}", names.join("|")),
        }
    }
}

/// A plugin's own description of a parameter, as a host sees it: what a host that links a
/// plugin's crate (rather than loading its library) parses `key=value` text against.
impl From<&crate::abi::author::ParamSpec> for ParamInfo {
    fn from(p: &crate::abi::author::ParamSpec) -> Self {
        use crate::abi::author::ParamType;
        ParamInfo {
            name: p.name.to_string(),
            help: p.help.to_string(),
            kind: match p.ty {
                ParamType::Float => ParamKind::Float,
                ParamType::Int => ParamKind::Int,
                ParamType::Bool => ParamKind::Bool,
                ParamType::Choice(names) => {
                    ParamKind::Choice(names.iter().map(|n| n.to_string()).collect())
                }
            },
            min: p.min,
            max: p.max,
            default: p.default,
        }
    }
}

/// A `key=value` that does not fit the plugin's parameters.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    #[error("`{0}` is not key=value")]
    Shape(String),
    #[error("no parameter `{key}` (this plugin takes: {known})")]
    Unknown { key: String, known: String },
    #[error("parameter `{key}`: `{value}` is not {expected}")]
    Value {
        key: String,
        value: String,
        expected: String,
    },
    #[error("parameter `{0}` is given twice")]
    Repeated(String),
}

/// Every parameter's default, in order.
pub fn defaults(params: &[ParamInfo]) -> Vec<f64> {
    params.iter().map(|p| p.default).collect()
}

/// Values from `key=value,key=value` text (empty text: the defaults). Numbers must lie in the
/// range (and be whole for an int); a bool is `true`/`false`/`1`/`0`; a choice is one of its
/// names.
pub fn parse_values(params: &[ParamInfo], text: &str) -> Result<Vec<f64>, ParamError> {
    let mut values = defaults(params);
    let mut seen = vec![false; params.len()];
    for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (key, value) = item
            .split_once('=')
            .map(|(k, v)| (k.trim(), v.trim()))
            .ok_or_else(|| ParamError::Shape(item.to_string()))?;
        let i = params
            .iter()
            .position(|p| p.name == key)
            .ok_or_else(|| ParamError::Unknown {
                key: key.to_string(),
                known: Names(params).to_string(),
            })?;
        if std::mem::replace(&mut seen[i], true) {
            return Err(ParamError::Repeated(key.to_string()));
        }
        let p = &params[i];
        let bad = || ParamError::Value {
            key: key.to_string(),
            value: value.to_string(),
            expected: p.describe_type(),
        };
        values[i] = match &p.kind {
            ParamKind::Bool => match value.to_ascii_lowercase().as_str() {
                "true" | "1" | "yes" | "on" => 1.0,
                "false" | "0" | "no" | "off" => 0.0,
                _ => return Err(bad()),
            },
            ParamKind::Choice(names) => names
                .iter()
                .position(|n| n.eq_ignore_ascii_case(value))
                .ok_or_else(bad)? as f64,
            ParamKind::Float | ParamKind::Int => {
                let v: f64 = value.parse().map_err(|_| bad())?;
                let whole = p.kind == ParamKind::Int;
                if !(v >= p.min && v <= p.max) || (whole && v.fract() != 0.0) {
                    return Err(bad());
                }
                v
            }
        };
    }
    Ok(values)
}

struct Names<'a>(&'a [ParamInfo]);

impl fmt::Display for Names<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            return f.write_str("none");
        }
        for (i, p) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            f.write_str(&p.name)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Vec<ParamInfo> {
        vec![
            ParamInfo {
                name: "quality".into(),
                help: String::new(),
                kind: ParamKind::Choice(vec!["fast".into(), "default".into(), "high".into()]),
                min: 0.0,
                max: 2.0,
                default: 1.0,
            },
            ParamInfo {
                name: "bands".into(),
                help: String::new(),
                kind: ParamKind::Int,
                min: 1.0,
                max: 31.0,
                default: 7.0,
            },
            ParamInfo {
                name: "spectral".into(),
                help: String::new(),
                kind: ParamKind::Bool,
                min: 0.0,
                max: 1.0,
                default: 1.0,
            },
        ]
    }

    #[test]
    fn values_are_parsed_by_name_and_type_with_defaults_for_the_rest() {
        let p = params();
        assert_eq!(parse_values(&p, "").unwrap(), vec![1.0, 7.0, 1.0]);
        assert_eq!(
            parse_values(&p, "quality=high, spectral=false").unwrap(),
            vec![2.0, 7.0, 0.0]
        );
        assert_eq!(parse_values(&p, "bands=15").unwrap(), vec![1.0, 15.0, 1.0]);
    }

    #[test]
    fn bad_values_are_errors_naming_the_parameter() {
        let p = params();
        for (text, needle) in [
            ("bands=0", "bands"),
            ("bands=2.5", "bands"),
            ("bands=nan", "bands"),
            ("quality=best", "fast|default|high"),
            ("spectral=maybe", "spectral"),
            ("grid=3", "no parameter `grid`"),
            ("bands", "key=value"),
            ("bands=3,bands=4", "twice"),
        ] {
            let e = parse_values(&p, text).unwrap_err().to_string();
            assert!(e.contains(needle), "{text}: {e}");
        }
    }
}
