//! Settings for `train`, `expert`, `prefs` and `sim`: `--set key=value` (repeatable) and a TOML
//! file of `key = value` lines, read into the one typed settings list ([`Settings`]), the file
//! first and `--set` over it.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;

use super::arg_error::ArgError;
use crate::settings::Settings;

/// The settings flags the headless commands share.
#[derive(Debug, Args)]
pub struct OverrideArgs {
    /// Override a setting, e.g. `--set hidden=256,256 --set c=0.3` (repeatable; `GET
    /// /api/tasks` and the README list them).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_pair)]
    pub overrides: Vec<(String, String)>,
    /// A TOML file of `key = value` settings, applied before `--set`.
    #[arg(long)]
    pub config: Option<PathBuf>,
}

impl OverrideArgs {
    /// The TOML file's settings, then `--set`'s over them. A headless run has no session, so
    /// the session's own settings (`pace_hz`, `record`, ...) are refused here.
    pub fn settings(&self) -> anyhow::Result<Settings> {
        let from_file = match &self.config {
            Some(path) => read_toml(path)?,
            None => Settings::default(),
        };
        let from_flags =
            Settings::from_pairs(self.overrides.iter().map(|(k, v)| (k.as_str(), v.as_str())))
                .context("--set")?;
        let settings = from_file.merged(from_flags)?;
        let session_only = settings.session_keys_set();
        if !session_only.is_empty() {
            bail!(
                "{} only apply to the server's sessions, not to a headless run",
                session_only.join(", ")
            );
        }
        Ok(settings)
    }
}

/// One `key=value` pair, split at the first `=`.
pub fn parse_pair(s: &str) -> Result<(String, String), ArgError> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| ArgError::NotAPair(s.to_string()))?;
    if k.trim().is_empty() {
        return Err(ArgError::EmptyKey(s.to_string()));
    }
    Ok((k.trim().to_string(), v.trim().to_string()))
}

/// Read a TOML file of flat `key = value` settings.
pub fn read_toml(path: &Path) -> anyhow::Result<Settings> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let table: toml::Table = text
        .parse()
        .with_context(|| format!("parsing {} as TOML", path.display()))?;
    if let Some((k, _)) = table.iter().find(|(_, v)| v.is_table()) {
        bail!(
            "{}: {k} is a table; settings are flat `key = value` lines",
            path.display()
        );
    }
    let json = serde_json::to_value(&table)?;
    Settings::from_json(json).with_context(|| format!("reading settings from {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::query_rule::UcbForm;

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
    fn toml_files_and_flags_read_into_one_settings_list() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.toml");
        std::fs::write(
            &path,
            "hidden = [32, 32]\nc = 0.25\nucb = \"paper\"\nhuman_critic_mask = true\n",
        )
        .unwrap();
        let file = read_toml(&path).unwrap();
        assert_eq!(file.sac.hidden, Some(vec![32, 32]));
        assert_eq!(
            (file.query_rule.c, file.query_rule.ucb),
            (Some(0.25), Some(UcbForm::Paper))
        );
        assert_eq!(file.human_critic.human_critic_mask, Some(true));
        let args = OverrideArgs {
            overrides: vec![("c".into(), "0.5".into())],
            config: Some(path.clone()),
        };
        let merged = args.settings().unwrap();
        assert_eq!(
            (merged.query_rule.c, merged.sac.hidden),
            (Some(0.5), Some(vec![32, 32]))
        );
        let session = OverrideArgs {
            overrides: vec![("pace_hz".into(), "5".into())],
            config: None,
        };
        assert!(
            session
                .settings()
                .unwrap_err()
                .to_string()
                .contains("pace_hz")
        );
        for bad in [
            "[section]\nx = 1\n",
            "not toml at all ===",
            "no_such_key = 1\n",
        ] {
            std::fs::write(&path, bad).unwrap();
            assert!(read_toml(&path).is_err(), "{bad}");
        }
    }
}
