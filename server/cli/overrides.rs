//! Hyper-parameter overrides for `train` and `expert`: `--set key=value` (repeatable) and a
//! TOML file of `key = value` lines, applied to a run's config in that order.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;

use crate::guidance::evaluative_run::EvaluativeRunConfig;

/// The override flags `train` and `expert` share.
#[derive(Debug, Args)]
pub struct OverrideArgs {
    /// Override a hyper-parameter, e.g. `--set hidden=256,256 --set c=0.3` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_pair)]
    pub overrides: Vec<(String, String)>,
    /// A TOML file of `key = value` overrides, applied before `--set`.
    #[arg(long)]
    pub config: Option<PathBuf>,
}

/// One `key=value` pair, split at the first `=`.
pub fn parse_pair(s: &str) -> Result<(String, String), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected key=value, got {s:?}"))?;
    if k.trim().is_empty() {
        return Err(format!("empty key in {s:?}"));
    }
    Ok((k.trim().to_string(), v.trim().to_string()))
}

/// Read a TOML file of flat `key = value` entries as strings, in file order.
pub fn read_toml(path: &Path) -> anyhow::Result<Vec<(String, String)>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let table: toml::Table = text
        .parse()
        .with_context(|| format!("parsing {} as TOML", path.display()))?;
    table
        .into_iter()
        .map(|(k, v)| {
            let value = match v {
                toml::Value::String(s) => s,
                toml::Value::Integer(i) => i.to_string(),
                toml::Value::Float(f) => f.to_string(),
                toml::Value::Boolean(b) => b.to_string(),
                toml::Value::Array(items) => items
                    .iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(","),
                other => bail!("{}: {k} = {other} is not a plain value", path.display()),
            };
            Ok((k, value))
        })
        .collect()
}

/// Apply one override (see `EvaluativeRunConfig::set`).
pub fn apply(config: &mut EvaluativeRunConfig, key: &str, value: &str) -> Result<(), String> {
    config.set(key, value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::feedback_schedule::EvaluativeMethod;
    use crate::guidance::query_rule::UcbForm;
    use crate::scene_graph::SceneGraph;
    use crate::sim::Task;

    #[test]
    fn pairs_split_at_the_first_equals_sign() {
        assert_eq!(
            parse_pair("hidden=256,256").unwrap(),
            ("hidden".into(), "256,256".into())
        );
        assert_eq!(parse_pair(" c = 0.3 ").unwrap(), ("c".into(), "0.3".into()));
        assert!(parse_pair("novalue").is_err());
        assert!(parse_pair("=3").is_err());
    }

    #[test]
    fn query_rule_keys_and_errors() {
        let mut config = EvaluativeRunConfig::new(Task::LunarLander, EvaluativeMethod::Dref, 0);
        apply(&mut config, "c", "0.5").unwrap();
        apply(&mut config, "k", "7").unwrap();
        apply(&mut config, "ucb", "paper").unwrap();
        apply(&mut config, "side_engines_on_a0", "true").unwrap();
        assert_eq!(
            (
                config.query_rule.c,
                config.query_rule.k,
                config.query_rule.form
            ),
            (0.5, 7, UcbForm::Paper)
        );
        assert_eq!(
            config.scene_graph,
            SceneGraph::LunarLander {
                side_engines_on_a0: true
            }
        );
        assert!(apply(&mut config, "k", "-1").unwrap_err().contains("k=-1"));
        assert!(apply(&mut config, "ucb", "best").is_err());
        let mut reaching = EvaluativeRunConfig::new(Task::Reaching, EvaluativeMethod::Dref, 0);
        assert!(apply(&mut reaching, "side_engines_on_a0", "true").is_err());
    }

    #[test]
    fn toml_values_become_strings() {
        let dir = std::env::temp_dir().join(format!("dualrep-overrides-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("run.toml");
        std::fs::write(
            &path,
            "hidden = [32, 32]\nc = 0.25\nucb = \"paper\"\nhuman_critic_mask = true\n",
        )
        .unwrap();
        let pairs = read_toml(&path).unwrap();
        assert!(pairs.contains(&("hidden".into(), "32,32".into())));
        assert!(pairs.contains(&("c".into(), "0.25".into())));
        assert!(pairs.contains(&("ucb".into(), "paper".into())));
        std::fs::write(&path, "[section]\nx = 1\n").unwrap();
        assert!(read_toml(&path).is_err());
        std::fs::write(&path, "not toml at all ===").unwrap();
        assert!(read_toml(&path).is_err());
    }
}
