//! The command line: every command's output formats and its errors.

mod arguments;
mod bad_inputs;
mod commands;
mod inputs_and_outputs;
mod plots;
mod reliability;
mod sensitivity_and_bode;
mod serve;
mod user_files;
