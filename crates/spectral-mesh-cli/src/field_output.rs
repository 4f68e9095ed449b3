//! The output options of the commands that draw one field: above the engine and the
//! figure code, which take their file checks and writes from `output` (so `output`
//! imports neither).

use std::path::PathBuf;

use anyhow::Result;
use spectral_mesh::analysis::{Analysis, Field};

use crate::engine::save_field_experiment;
use crate::figure::{FigureArgs, write_field};
use crate::input::MeshInfo;
use crate::output::{FIGURE_EXTS, check_experiment_file, check_outputs};

/// The output options every command that draws one field shares (`heat`, `distance`,
/// `signature`, `segment`): the experiment file that replays the field, overwriting, and
/// how the field is drawn. The output files themselves stay with each command (their help
/// and whether they are required differ).
#[derive(Debug, clap::Args)]
pub struct FieldOutputArgs {
    /// Also write an experiment file that reproduces the drawn field with `run FILE.toml`.
    #[arg(long, value_name = "FILE.toml")]
    pub save_experiment: Option<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
    #[command(flatten)]
    pub figure: FigureArgs,
}

impl FieldOutputArgs {
    /// Checks before any work that `outs` are field outputs that may be written, and that
    /// the experiment file may be.
    pub fn check(&self, outs: &[PathBuf]) -> Result<()> {
        check_outputs(outs, &FIGURE_EXTS, self.force)?;
        check_experiment_file(self.save_experiment.as_ref(), self.force)
    }

    /// Draws or writes `field` to each of `outs` (by extension), naming them on stdout.
    pub fn write_field(&self, an: &Analysis, field: &Field, outs: &[PathBuf]) -> Result<()> {
        write_field(an, field, outs, self.figure.options())
    }

    /// Writes the experiment file that replays `field`, when `--save-experiment` asks
    /// for one.
    pub fn save_experiment(
        &self,
        info: &MeshInfo,
        an: &Analysis,
        field: &Field,
        repair: bool,
    ) -> Result<()> {
        match &self.save_experiment {
            Some(file) => save_field_experiment(
                file,
                info,
                an,
                field,
                repair,
                &self.figure.options(),
                self.force,
            ),
            None => Ok(()),
        }
    }
}
