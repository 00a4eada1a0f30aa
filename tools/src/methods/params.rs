//! A method's parameters as data: name, meaning, kind with its range, default, and whether the
//! bake or the run time reads it. One declaration serves every front end: `relume bake` and
//! `relume render` flags (`--name VALUE`, listed by `--help` and `relume methods`), sweep
//! keys (`name = value`), and the values a method's bake and techniques read.

use anyhow::{bail, Result};
use relume_bake::settings::ValueRange;
use std::collections::BTreeMap;

/// When a parameter is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stage {
    /// By the bake: changing it means another bake artifact.
    Bake,
    /// By the renderer: one bake serves every value.
    Render,
}

/// What values a parameter takes.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Kind {
    /// A whole number (`ValueRange::Count`) or a finite number (`ValueRange::Number`) in the range the
    /// bake's own check accepts.
    Range(ValueRange),
    /// One of these words.
    Choice(&'static [&'static str]),
    /// Given or not.
    Flag,
    /// A file or folder, as given (relative to the working folder).
    Path,
}

/// What a parameter is when it is not given.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Default {
    /// This value.
    Value(&'static str),
    /// Taken from the scene (or made by the method), as the text says.
    From(&'static str),
}

#[derive(Debug)]
pub(crate) struct Param {
    /// Kebab-case: the flag `--name` and the sweep key `name`.
    pub name: &'static str,
    pub help: &'static str,
    pub kind: Kind,
    pub default: Default,
    pub stage: Stage,
}

impl Param {
    /// A bake parameter (the run time's: [`Param::at_render`]) taking a whole number.
    pub const fn count(name: &'static str, help: &'static str, min: u64, max: u64, default: Default) -> Param {
        Param::within(name, help, ValueRange::count(min, max), default)
    }

    /// A bake parameter taking a finite number in `min..=max` (above `min` when `above`).
    pub const fn number(name: &'static str, help: &'static str, (min, max, above): (f64, f64, bool), default: Default) -> Param {
        Param::within(name, help, ValueRange::number(min, max, above), default)
    }

    /// A bake parameter taking what `range` admits: a setting's own range, which its bake
    /// checks.
    pub const fn within(name: &'static str, help: &'static str, range: ValueRange, default: Default) -> Param {
        Param { name, help, kind: Kind::Range(range), default, stage: Stage::Bake }
    }

    /// A bake parameter taking one of `choices`.
    pub const fn choice(name: &'static str, help: &'static str, choices: &'static [&'static str], default: Default) -> Param {
        Param { name, help, kind: Kind::Choice(choices), default, stage: Stage::Bake }
    }

    /// A bake parameter naming a file or folder (its default: what the method does without).
    pub const fn path(name: &'static str, help: &'static str, default: &'static str) -> Param {
        Param { name, help, kind: Kind::Path, default: Default::From(default), stage: Stage::Bake }
    }

    /// A bake flag.
    pub const fn flag(name: &'static str, help: &'static str) -> Param {
        Param { name, help, kind: Kind::Flag, default: Default::Value("false"), stage: Stage::Bake }
    }

    /// The same parameter, read at run time.
    pub const fn at_render(self) -> Param {
        Param { stage: Stage::Render, ..self }
    }

    /// The range or choices, as `--help` and `relume methods` show them.
    pub fn range(&self) -> String {
        match self.kind {
            Kind::Range(range) => range.text(),
            Kind::Choice(choices) => choices.join(", "),
            Kind::Flag => "a flag".into(),
            Kind::Path => "a path".into(),
        }
    }

    pub fn default_text(&self) -> String {
        match self.default {
            Default::Value(v) => v.to_string(),
            Default::From(how) => how.to_string(),
        }
    }

    /// `text` checked against the kind and range.
    fn parse(&self, text: &str) -> Result<Value> {
        let name = self.name;
        Ok(match self.kind {
            Kind::Range(range @ ValueRange::Count { .. }) => match text.parse::<u64>() {
                Ok(v) if range.admits_count(v) => Value::Count(v),
                _ => bail!("--{name} {text}: give a whole number in {}", self.range()),
            },
            Kind::Range(range) => match text.parse::<f64>() {
                Ok(v) if range.admits(v) => Value::Number(v),
                _ => bail!("--{name} {text}: give a finite number in {}", self.range()),
            },
            Kind::Choice(choices) => match choices.iter().find(|c| **c == text) {
                Some(choice) => Value::Choice(choice),
                None => bail!("--{name} {text}: give one of {}", choices.join(", ")),
            },
            Kind::Flag => match text {
                "true" => Value::Flag,
                _ => bail!("--{name} takes no value ({text})"),
            },
            Kind::Path if text.is_empty() => bail!("--{name}: give a path"),
            Kind::Path => Value::Path(text.to_string()),
        })
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Value {
    Count(u64),
    Number(f64),
    Choice(&'static str),
    Flag,
    Path(String),
}

/// The values given to one method, checked; defaults are applied where they are read.
#[derive(Clone, Debug, Default)]
pub(crate) struct Values {
    given: BTreeMap<&'static str, Value>,
    /// The given values' text, in the order given, for labels and the manifest.
    texts: Vec<(&'static str, String)>,
}

impl Values {
    /// Parses `(name, text)` pairs for a method whose parameters are `params`; a flag's text is
    /// "true". Refused, naming the parameter: one the method does not take (listing those it
    /// does), one given twice, and a value out of its kind or range.
    pub fn parse(method: &str, params: &[&'static Param], pairs: &[(String, String)]) -> Result<Values> {
        let mut values = Values::default();
        for (name, text) in pairs {
            let Some(param) = params.iter().find(|p| p.name == name) else {
                let known: Vec<&str> = params.iter().map(|p| p.name).collect();
                let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                bail!("--{name}: not a parameter of {method} (its parameters: {known}; `relume methods {method}` describes them)");
            };
            if values.given.insert(param.name, param.parse(text)?).is_some() {
                bail!("--{name} given twice");
            }
            values.texts.push((param.name, text.clone()));
        }
        Ok(values)
    }

    /// Whether `param` was given (a flag: whether it is set).
    pub fn given(&self, param: &Param) -> bool {
        self.given.contains_key(param.name)
    }

    /// A count, given or its declared default.
    pub fn count(&self, param: &Param) -> u64 {
        match self.value(param) {
            Value::Count(v) => v,
            _ => wrong_kind(param),
        }
    }

    /// A number, given or its declared default.
    pub fn number(&self, param: &Param) -> f64 {
        match self.value(param) {
            Value::Number(v) => v,
            _ => wrong_kind(param),
        }
    }

    /// A choice, given or its declared default.
    pub fn choice(&self, param: &Param) -> &'static str {
        match self.value(param) {
            Value::Choice(v) => v,
            _ => wrong_kind(param),
        }
    }

    /// A path if given.
    pub fn given_path(&self, param: &Param) -> Option<std::path::PathBuf> {
        match self.given.get(param.name)? {
            Value::Path(path) => Some(path.into()),
            _ => wrong_kind(param),
        }
    }

    /// A count if given: for a parameter whose default comes from elsewhere.
    pub fn given_count(&self, param: &Param) -> Option<u64> {
        self.given(param).then(|| self.count(param))
    }

    /// A number if given: for a parameter whose default comes from elsewhere.
    pub fn given_number(&self, param: &Param) -> Option<f64> {
        self.given(param).then(|| self.number(param))
    }

    /// A choice if given: for a parameter whose default comes from elsewhere.
    pub fn given_choice(&self, param: &Param) -> Option<&'static str> {
        self.given(param).then(|| self.choice(param))
    }

    /// Its given value, or its declared default; a parameter whose default comes from
    /// elsewhere is read with the `given_` accessors (a slip in relume, not in the input).
    fn value(&self, param: &Param) -> Value {
        if let Some(v) = self.given.get(param.name) {
            return v.clone();
        }
        match param.default {
            Default::Value(text) => param.parse(text).expect("a parameter's default is in its range"),
            Default::From(_) => panic!("--{} has no declared default: read it with a given_ accessor", param.name),
        }
    }

    /// The given values of one stage, as `name=value` pairs: what tells two bakes apart.
    pub fn of_stage(&self, params: &[&'static Param], stage: Stage) -> Vec<String> {
        let staged = |name: &str| params.iter().any(|p| p.name == name && p.stage == stage);
        self.texts.iter().filter(|(name, _)| staged(name)).map(|(name, text)| format!("{name}={text}")).collect()
    }

    /// The given values of one stage as JSON (numbers as numbers), for the artifact's manifest.
    pub fn json(&self, params: &[&'static Param], stage: Stage) -> serde_json::Value {
        let staged = |name: &str| params.iter().any(|p| p.name == name && p.stage == stage);
        let entries = self.given.iter().filter(|(name, _)| staged(name)).map(|(name, value)| {
            let v = match value {
                Value::Count(v) => serde_json::json!(v),
                Value::Number(v) => serde_json::json!(v),
                Value::Choice(v) => serde_json::json!(v),
                Value::Flag => serde_json::json!(true),
                Value::Path(v) => serde_json::json!(v),
            };
            (name.to_string(), v)
        });
        serde_json::Value::Object(entries.collect())
    }
}

fn wrong_kind(param: &Param) -> ! {
    panic!("--{} read as another kind than it declares", param.name)
}

/// Every parameter of `methods`, each once, in order of first appearance.
pub(crate) fn all_params(methods: &[&dyn super::Method]) -> Vec<&'static Param> {
    let mut all: Vec<&'static Param> = Vec::new();
    for method in methods {
        for param in method.params() {
            if !all.iter().any(|p| p.name == param.name) {
                all.push(param);
            }
        }
    }
    all
}

/// One method's parameters as `relume methods NAME` prints them.
pub(crate) fn describe(method: &dyn super::Method) -> String {
    use std::fmt::Write as _;
    let mut text = format!("{}: {}\n", method.name(), method.description());
    let params = method.params();
    if params.is_empty() {
        text.push_str("  no parameters\n");
    }
    for p in params {
        let stage = match p.stage {
            Stage::Bake => "bake",
            Stage::Render => "render",
        };
        let _ = writeln!(text, "  --{:<22} {} [{stage}; {}; default {}]", p.name, p.help, p.range(), p.default_text());
    }
    text
}

/// The method parameters of a command line (`relume bake`: the bake's; `relume render`: the
/// run time's): every such parameter of every registered method, each an optional
/// `--name VALUE` (a flag takes no value), gathered as text to be parsed once the method is
/// known.
#[derive(Clone, Debug, Default)]
pub(crate) struct ParamArgs<const BAKE: bool> {
    pub pairs: Vec<(String, String)>,
}

/// The parameters `relume bake` takes (the bake's).
pub(crate) type BakeParams = ParamArgs<true>;
/// The parameters `relume render` takes (the run-time ones).
pub(crate) type RenderParams = ParamArgs<false>;

impl<const BAKE: bool> ParamArgs<BAKE> {
    fn params() -> Vec<&'static Param> {
        let stage = if BAKE { Stage::Bake } else { Stage::Render };
        all_params(&super::METHODS).into_iter().filter(|p| p.stage == stage).collect()
    }

    /// The parameters as the command line that gives them (a flag without its value).
    pub fn argv(&self) -> Vec<String> {
        let flag = |name: &str| Self::params().iter().any(|p| p.name == name && matches!(p.kind, Kind::Flag));
        self.pairs
            .iter()
            .flat_map(|(name, value)| match flag(name) {
                true => vec![format!("--{name}")],
                false => vec![format!("--{name}"), value.clone()],
            })
            .collect()
    }
}

impl<const BAKE: bool> clap::FromArgMatches for ParamArgs<BAKE> {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut pairs = Vec::new();
        for param in Self::params() {
            match param.kind {
                Kind::Flag if matches.get_flag(param.name) => pairs.push((param.name.to_string(), "true".to_string())),
                Kind::Flag => {}
                _ => {
                    if let Some(text) = matches.get_one::<String>(param.name) {
                        pairs.push((param.name.to_string(), text.clone()));
                    }
                }
            }
        }
        Ok(ParamArgs { pairs })
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl<const BAKE: bool> clap::Args for ParamArgs<BAKE> {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        Self::params().into_iter().fold(cmd, |cmd, param| {
            let help =
                format!("{} [{}; {}; default {}]", param.help, super::takers(param.name).join(", "), param.range(), param.default_text());
            let arg = clap::Arg::new(param.name).long(param.name).help(help).help_heading("Method parameters (relume methods NAME)");
            cmd.arg(match param.kind {
                Kind::Flag => arg.action(clap::ArgAction::SetTrue),
                // Checked here too, so that a value out of range is a usage error, as clap's own.
                _ => arg
                    .value_name("VALUE")
                    .action(clap::ArgAction::Set)
                    .value_parser(move |text: &str| param.parse(text).map(|_| text.to_string()).map_err(|e| e.to_string())),
            })
        })
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}
