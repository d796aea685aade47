//! The `main` of a report plugin.
//!
//! The launcher runs each `[[report]]` executable twice: before the group starts, as
//! `PROGRAM --check`, so bad params stop the launch with nothing started; and after the run,
//! as `PROGRAM RUN_DIR`, to write its sections. Both times the entry's `params` come as JSON
//! in `CARAVAN_PARAMS` and the launch file's directory in `CARAVAN_LAUNCH_DIR`. Exit codes:
//! 0 done, 2 bad params or input, 1 a failure while computing. `PROGRAM --describe-params`
//! prints the params as a JSON Schema, as every node does ([`caravan::describe_params`]).

use crate::{RecordedMessage, RunFacts, Section};
use serde::de::DeserializeOwned;
use std::cell::OnceCell;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Where a plugin's relative paths start: the directory of the launch file that named it.
pub struct Inputs {
    pub launch_dir: PathBuf,
}

impl Inputs {
    /// `path` relative to the launch file (absolute paths stay as they are).
    pub fn path(&self, path: impl AsRef<Path>) -> PathBuf {
        self.launch_dir.join(path)
    }
}

/// One finished run: its directory, the launcher's facts and (read on first use) its
/// recording.
pub struct Run {
    pub dir: PathBuf,
    pub facts: RunFacts,
    messages: OnceCell<Vec<RecordedMessage>>,
}

impl Run {
    pub fn open(dir: &Path) -> anyhow::Result<Self> {
        Ok(Self {
            dir: dir.to_path_buf(),
            facts: RunFacts::load(dir)?,
            messages: OnceCell::new(),
        })
    }

    /// Every recorded message, in file order.
    pub fn messages(&self) -> anyhow::Result<&[RecordedMessage]> {
        if self.messages.get().is_none() {
            let read = crate::read_all(&self.dir.join(crate::RECORDING_FILE))?;
            let _ = self.messages.set(read);
        }
        Ok(self.messages.get().map(Vec::as_slice).unwrap_or_default())
    }
}

/// A report plugin: built from its params (checked before the run starts), then asked for
/// the sections of a run.
pub trait ReportPlugin: Sized {
    type Params: DeserializeOwned + caravan::schemars::JsonSchema;

    /// Checks the params and loads what they name; an error names the key.
    fn new(params: Self::Params, inputs: &Inputs) -> Result<Self, String>;

    /// The sections of `run`; none when the run is not the plugin's kind of run. Plots and
    /// other files go into `run.dir`.
    fn sections(&self, run: &Run) -> anyhow::Result<Vec<Section>>;
}

/// Runs plugin `P` as a process (see the module documentation).
pub fn main<P: ReportPlugin>(program: &str) -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let fail = |code: u8, message: String| {
        eprintln!("{program}: {message}");
        ExitCode::from(code)
    };
    let run_dir = match args.as_slice() {
        [flag] if flag == caravan::DESCRIBE_PARAMS_FLAG => {
            caravan::print_params_description::<P::Params>();
            return ExitCode::SUCCESS;
        }
        [flag] if flag == "--check" => None,
        [dir] if !dir.starts_with('-') => Some(PathBuf::from(dir)),
        _ => {
            return fail(
                2,
                format!("usage: {program} --check | {program} RUN_DIR (params in CARAVAN_PARAMS)"),
            );
        }
    };
    let env = |var: &str| std::env::var(var).ok();
    let params_json = env(caravan::env_vars::PARAMS).unwrap_or_else(|| "{}".into());
    let value: serde_json::Value = match serde_json::from_str(&params_json) {
        Ok(v) => v,
        Err(e) => return fail(2, format!("{} is not JSON: {e}", caravan::env_vars::PARAMS)),
    };
    let params: P::Params = match caravan::parse_params(program, &value) {
        Ok(p) => p,
        Err(caravan::Error::Params { message, .. }) => {
            return fail(2, format!("params of report '{program}': {message}"));
        }
        Err(e) => return fail(2, e.to_string()),
    };
    let inputs = Inputs {
        launch_dir: env(caravan::env_vars::LAUNCH_DIR).map_or_else(|| ".".into(), PathBuf::from),
    };
    let plugin = match P::new(params, &inputs) {
        Ok(p) => p,
        Err(e) => return fail(2, format!("params of report '{program}': {e}")),
    };
    let Some(dir) = run_dir else {
        return ExitCode::SUCCESS;
    };
    let written = Run::open(&dir).and_then(|run| {
        for section in plugin.sections(&run)? {
            section.write(&dir)?;
        }
        Ok(())
    });
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(1, format!("{e:#}")),
    }
}
