//! `bikedyn serve`: the explorer page on localhost until interrupted.

use anyhow::Result;
use bikedyn::serve::{ServeOptions, Server};
use std::io::Write;
use std::path::PathBuf;

/// Run `bikedyn serve`.
pub fn run(dir: PathBuf, port: u16) -> Result<bool> {
    let server = Server::bind(&ServeOptions { dir, port })?;
    outln!("the stability explorer: {} (Ctrl-C stops)", server.url());
    // The address line reaches a script that waits for it at once.
    std::io::stdout().flush()?;
    server.run(&|line| eprintln!("{line}"));
    Ok(true)
}
