//! What a sweep runs: its points (an algorithm with its parameters, `NAME[:k=v,…]`), grouped
//! into series — the quality presets, each `--algo`, and each `--vary`ed parameter.

use flarebench_sdk::abi::params::{ParamInfo, parse_values};
use ghost_raytrace::scene::Quality;
use serde::{Deserialize, Serialize};

/// The ghost renderer linked into the workbench: run in-process, so its plan and its ghosts
/// one by one can be measured (a plugin library is timed through the ABI as a whole).
pub const BUILTIN: &str = "ghost-raytrace";

/// One point of a sweep.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Point {
    /// The series (line on the plot) the point belongs to.
    pub series: String,
    /// The point's name within its series.
    pub label: String,
    /// `NAME[:key=value,…]`: a plugin name or library path with its parameters.
    pub algo: String,
}

/// `--vary KEY=a,b,c`.
#[derive(Clone, Debug, PartialEq)]
pub struct Vary {
    pub key: String,
    pub values: Vec<String>,
}

impl Vary {
    pub fn parse(s: &str) -> Result<Vary, String> {
        let (key, values) = s
            .split_once('=')
            .ok_or_else(|| format!("`{s}`: expected KEY=a,b,c"))?;
        let key = key.trim().to_string();
        let values: Vec<String> = values
            .split(',')
            .map(str::trim)
            .filter(|v| !v.is_empty())
            .map(str::to_string)
            .collect();
        if key.is_empty() || values.is_empty() {
            return Err(format!(
                "`{s}`: expected KEY=a,b,c (a key and at least one value)"
            ));
        }
        Ok(Vary { key, values })
    }
}

/// What the default sweep varies on the default preset: each threshold of the planner that
/// leaves something out, over a range around its preset value (docs/accuracy.md § Sweeps).
pub fn default_vary() -> Vec<Vary> {
    let v = |key: &str, values: &[&str]| Vary {
        key: key.to_string(),
        values: values.iter().map(|s| s.to_string()).collect(),
    };
    vec![
        v("dim_budget", &["0.0003", "0.001", "0.003", "0.01", "0.03"]),
        v("band_spacing", &["0.25", "0.5", "1", "2"]),
        v("coarse_px", &["32", "64", "96", "192"]),
        v("grid_scale", &["0.5", "0.75", "1", "1.5"]),
    ]
}

/// The algorithm's name (or library path) and its parameter text.
pub fn split_algo(spec: &str) -> (&str, &str) {
    spec.split_once(':').unwrap_or((spec, ""))
}

/// `spec` with `key=value` set (replacing the key's value if `spec` names it).
pub fn with_param(spec: &str, key: &str, value: &str) -> String {
    let (name, text) = split_algo(spec);
    let mut items: Vec<String> = text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .filter(|s| s.split_once('=').map_or(*s, |(k, _)| k).trim() != key)
        .map(str::to_string)
        .collect();
    items.push(format!("{key}={value}"));
    format!("{name}:{}", items.join(","))
}

/// The points of a sweep. `params` gives an algorithm's parameters by name or path (loading
/// a plugin to ask it). With no quality, algorithm or variation given, the default sweep:
/// every preset, and [`default_vary`] on the default preset.
pub fn build(
    qualities: Option<&[Quality]>,
    algos: &[String],
    vary: &[Vary],
    product: bool,
    mut params: impl FnMut(&str) -> anyhow::Result<Vec<ParamInfo>>,
) -> anyhow::Result<Vec<Point>> {
    let default_sweep = qualities.is_none() && algos.is_empty() && vary.is_empty();
    let default_vary = default_vary();
    let (qualities, vary) = if default_sweep {
        (Some(&Quality::ALL[..]), &default_vary[..])
    } else {
        (qualities, vary)
    };
    let mut points = Vec::new();
    for &q in qualities.unwrap_or(&[]) {
        points.push(Point {
            series: format!("{BUILTIN} presets"),
            label: format!("quality={q}"),
            algo: format!("{BUILTIN}:quality={q}"),
        });
    }
    for a in algos {
        points.push(Point {
            series: a.clone(),
            label: a.clone(),
            algo: a.clone(),
        });
    }
    let bases: Vec<String> = if algos.is_empty() {
        vec![format!("{BUILTIN}:quality={}", Quality::Default)]
    } else {
        algos.to_vec()
    };
    let mut known = Vec::new();
    for b in &bases {
        known.push(params(split_algo(b).0)?);
    }
    let knows = |i: usize, key: &str| known[i].iter().any(|p| p.name == key);
    if product && !vary.is_empty() {
        let keys: Vec<&str> = vary.iter().map(|v| v.key.as_str()).collect();
        let mut any = false;
        for (i, b) in bases.iter().enumerate() {
            if !keys.iter().all(|k| knows(i, k)) {
                continue;
            }
            any = true;
            let series = format!("{b} · {}", keys.join("×"));
            let mut combos: Vec<Vec<(&str, &str)>> = vec![vec![]];
            for v in vary {
                combos = combos
                    .into_iter()
                    .flat_map(|c| {
                        v.values.iter().map(move |x| {
                            let mut c = c.clone();
                            c.push((v.key.as_str(), x.as_str()));
                            c
                        })
                    })
                    .collect();
            }
            for c in combos {
                let mut algo = b.clone();
                for (k, x) in &c {
                    algo = with_param(&algo, k, x);
                }
                let label = c
                    .iter()
                    .map(|(k, x)| format!("{k}={x}"))
                    .collect::<Vec<_>>()
                    .join(",");
                points.push(Point {
                    series: series.clone(),
                    label,
                    algo,
                });
            }
        }
        anyhow::ensure!(
            any,
            "--product: no algorithm has every varied parameter ({})",
            keys.join(", ")
        );
    } else {
        for v in vary {
            let mut any = false;
            for (i, b) in bases.iter().enumerate() {
                if !knows(i, &v.key) {
                    continue;
                }
                any = true;
                for x in &v.values {
                    points.push(Point {
                        series: format!("{b} · {}", v.key),
                        label: format!("{}={x}", v.key),
                        algo: with_param(b, &v.key, x),
                    });
                }
            }
            if !any {
                let names: Vec<String> = known
                    .iter()
                    .flatten()
                    .map(|p| p.name.clone())
                    .collect::<std::collections::BTreeSet<_>>()
                    .into_iter()
                    .collect();
                anyhow::bail!(
                    "--vary {}: no algorithm of the sweep has a parameter `{}` (they have: {})",
                    v.key,
                    v.key,
                    names.join(", ")
                );
            }
        }
    }
    // Every point's parameters must parse before anything runs.
    for p in &points {
        let (name, text) = split_algo(&p.algo);
        let info = params(name)?;
        parse_values(&info, text).map_err(|e| anyhow::anyhow!("{}: {e}", p.algo))?;
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flarebench_sdk::abi::params::ParamKind;

    fn float(name: &str) -> ParamInfo {
        ParamInfo {
            name: name.to_string(),
            help: String::new(),
            kind: ParamKind::Float,
            min: -1.0,
            max: 100.0,
            default: 0.0,
        }
    }

    fn builtin_params(_: &str) -> anyhow::Result<Vec<ParamInfo>> {
        Ok(vec![
            ParamInfo {
                name: "quality".to_string(),
                help: String::new(),
                kind: ParamKind::Choice(vec!["fast".into(), "default".into(), "high".into()]),
                min: 0.0,
                max: 2.0,
                default: 1.0,
            },
            float("dim_budget"),
            float("grid_scale"),
        ])
    }

    #[test]
    fn with_param_adds_or_replaces() {
        assert_eq!(with_param("a", "k", "1"), "a:k=1");
        assert_eq!(with_param("a:x=2", "k", "1"), "a:x=2,k=1");
        assert_eq!(with_param("a:k=3,x=2", "k", "1"), "a:x=2,k=1");
    }

    #[test]
    fn the_default_sweep_has_the_presets_and_every_threshold() {
        let real = |_: &str| Ok(crate::sweep::measure::builtin_params());
        let pts = build(None, &[], &[], false, real).unwrap();
        assert_eq!(pts.len(), 3 + 5 + 4 + 4 + 4);
        assert_eq!(pts[2].algo, "ghost-raytrace:quality=high");
        assert_eq!(pts[3].series, "ghost-raytrace:quality=default · dim_budget");
        assert_eq!(
            pts[19].algo,
            "ghost-raytrace:quality=default,grid_scale=1.5"
        );
        // A parameter list without the thresholds: an error naming the first missing one.
        let e = build(None, &[], &[], false, builtin_params)
            .unwrap_err()
            .to_string();
        assert!(e.contains("band_spacing"), "{e}");
    }

    #[test]
    fn vary_makes_one_series_per_key_and_product_one_per_base() {
        let vary = [
            Vary::parse("dim_budget=0.001,0.01").unwrap(),
            Vary::parse("grid_scale=0.5,1").unwrap(),
        ];
        let pts = build(Some(&[Quality::Fast]), &[], &vary, false, builtin_params).unwrap();
        assert_eq!(pts.len(), 1 + 2 + 2);
        assert_eq!(pts[0].algo, "ghost-raytrace:quality=fast");
        assert_eq!(pts[1].series, "ghost-raytrace:quality=default · dim_budget");
        assert_eq!(
            pts[1].algo,
            "ghost-raytrace:quality=default,dim_budget=0.001"
        );
        let pts = build(None, &[], &vary, true, builtin_params).unwrap();
        assert_eq!(pts.len(), 4);
        assert_eq!(pts[3].label, "dim_budget=0.01,grid_scale=1");
    }

    #[test]
    fn bad_keys_and_values_are_errors_before_anything_runs() {
        let e = build(
            None,
            &[],
            &[Vary::parse("nope=1").unwrap()],
            false,
            builtin_params,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("nope") && e.contains("dim_budget"), "{e}");
        let e = build(
            None,
            &[],
            &[Vary::parse("dim_budget=x").unwrap()],
            false,
            builtin_params,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("dim_budget=x"), "{e}");
        assert!(Vary::parse("k=").is_err() && Vary::parse("k").is_err());
    }
}
