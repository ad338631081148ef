//! `bikedyn params`: show a bicycle's parameters or convert between forms.

use super::args::{FormName, ParamsCommand};
use super::text::params_show_text;
use super::{emit, load};
use anyhow::Result;
use bikedyn::bicycle::files::ParameterFile;
use bikedyn::report::output;

/// Run `bikedyn params ...`.
pub fn run(command: ParamsCommand) -> Result<bool> {
    match command {
        ParamsCommand::Convert { to, file, output: out } => {
            super::Paths::new()
                .bike("FILE", Some(&file))
                .file("--output", out.as_deref())
                .check()?;
            let b = load(&file)?;
            let mut text = match to {
                FormName::Benchmark => b.parameters.to_benchmark()?.to_toml_string(),
                FormName::Thesis => b.thesis()?.to_toml_string(),
            };
            let effects = b.effects_toml();
            if !effects.is_empty() {
                text.push_str(&format!("\n# Effect parameters of {}:\n{effects}", b.name));
            }
            emit(&text, &out)?;
            Ok(true)
        }
        ParamsCommand::Show { file, bike, model } => {
            let b = load(file.as_deref().unwrap_or(&bike))?;
            out!("{}", params_show_text(&b, model.as_deref())?);
            // Derived geometry, whatever the form of the file (issue 10,
            // point 9), as TOML comments so the output still loads.
            let g = b.derived_geometry()?;
            outln!("\n# Derived geometry (Meijaard et al. 2007, appendix A; benchmark axes):");
            for (sym, value, unit, what) in g.rows() {
                outln!(
                    "# {sym:<8} = {:>14} {unit:<7} {what}",
                    output::format_significant(value, 8)
                );
            }
            Ok(true)
        }
    }
}
