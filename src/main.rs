//! `rocklab`: see `rocklab --help`.

use std::process::ExitCode;

mod cli;

fn main() -> ExitCode {
    match cli::run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", message(&e));
            ExitCode::from(2)
        }
    }
}

/// The error and its causes joined by ": ", a cause left out when the message
/// before it already holds it (issue 22: "Is a directory (os error 21): Is a
/// directory (os error 21)"), and at most 4,000 characters: the messages quote
/// short excerpts of bad values, this bounds what any message can grow to.
fn message(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let s = cause.to_string();
        if !msg.contains(&s) {
            if !msg.is_empty() {
                msg.push_str(": ");
            }
            msg.push_str(&s);
        }
    }
    rocklab::error::excerpt_text(&msg, 4000)
}
