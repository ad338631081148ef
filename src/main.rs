//! The `bikedyn` command line: parses arguments, calls the library, prints.
//! Each command lives in `cli/<command>.rs`; the argument types in
//! `cli/args.rs`.

use anyhow::Result;
use clap::{CommandFactory, FromArgMatches};
use cli::args::{Cli, Command};
use std::process::ExitCode;

/// `print!` to standard output that returns an error from the enclosing
/// function when the write fails (a closed pipe such as `| head -1`, a
/// full disk) instead of panicking as `print!` does.
macro_rules! out {
    ($($t:tt)*) => {
        crate::cli::write_out(format_args!($($t)*))?
    };
}

/// `println!` that returns the write error (see [`out!`]).
macro_rules! outln {
    () => {
        crate::cli::write_out(format_args!("\n"))?
    };
    ($($t:tt)*) => {
        crate::cli::write_out(format_args!("{}\n", format_args!($($t)*)))?
    };
}

mod cli;

fn run(cli: Cli) -> Result<bool> {
    match cli.command {
        Command::Report { out } => cli::report::run(out),
        Command::Verify {
            model,
            states,
            seed,
            json,
        } => cli::verify::run(model, states, seed, json),
        Command::Models { json } => cli::models::run(json),
        Command::Serve { dir, port } => cli::serve::run(dir, port),
        Command::Canonical { bike, speeds, json } => cli::canonical::run(bike, speeds, json),
        Command::Eig {
            bike,
            speeds,
            out,
            plot,
            plot_root_locus,
            plot_mode_shapes,
            speed,
            plot_args,
        } => cli::eig::run(
            bike,
            speeds,
            out,
            cli::eig::Plots {
                continuation: plot,
                root_locus: plot_root_locus,
                mode_shapes: plot_mode_shapes,
                speed,
                args: plot_args,
            },
        ),
        Command::Stability {
            bike,
            speed_max,
            json,
            monte_carlo,
            seed,
        } => cli::stability::run(bike, speed_max, json, monte_carlo.map(|n| (n, seed))),
        Command::Sweep(args) => cli::sweep::run(args),
        Command::Sensitivity {
            bike,
            form,
            speed,
            speed_max,
            out,
            plot,
            plot_args,
        } => cli::sensitivity::run(bike, form, speed, speed_max, out, plot, plot_args),
        Command::Bode {
            bike,
            speed,
            omega,
            points,
            out,
            plot,
            plot_args,
        } => cli::bode::run(bike, speed, omega, points, out, plot, plot_args),
        Command::Params { command } => cli::params::run(command),
        Command::Fit(args) => cli::fit::run(&args),
        Command::Identify(args) => cli::identify::run(&args),
        Command::Simulate(args) => cli::simulate::run(args),
        Command::Synth(args) => cli::synth::run(args),
        Command::Bench { quick, identify } => cli::bench::run(quick, identify),
    }
}

/// The error and its causes, each cause once: a cause whose text the
/// message already contains (errors that print their source) is skipped.
/// Every part is cut to `MAX_PART` characters, so a junk input line is not
/// echoed whole.
fn error_message(e: &anyhow::Error) -> String {
    const MAX_PART: usize = 400;
    let mut msg = String::new();
    for cause in e.chain() {
        let mut part = cause.to_string();
        if msg.contains(&part) {
            continue;
        }
        let n = part.chars().count();
        if n > MAX_PART {
            part = part.chars().take(MAX_PART).collect::<String>() + &format!("... ({} more characters)", n - MAX_PART);
        }
        if !msg.is_empty() {
            msg += ": ";
        }
        msg += &part;
    }
    msg
}

fn main() -> ExitCode {
    // Flush here so that a failed final write is an error too (at exit it
    // would be ignored).
    // Negative numbers are values, not flags (`--speed -5`, `--values
    // -1:1:0.1`), in every command.
    let command = Cli::command().mut_subcommands(|c| c.allow_negative_numbers(true));
    let cli = match Cli::from_arg_matches(&command.get_matches()) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    cli::set_verbose(cli.verbose);
    bikedyn::bicycle::allow_implausible_units(cli.allow_units);
    let result = run(cli).and_then(|ok| {
        use std::io::Write;
        std::io::stdout().flush().map_err(cli::stdout_error)?;
        Ok(ok)
    });
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) if e.downcast_ref::<cli::StdoutClosed>().is_some() => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_message(&e));
            ExitCode::from(2)
        }
    }
}
