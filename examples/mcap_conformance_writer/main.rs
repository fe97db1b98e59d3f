//! The MCAP conformance suite's writer program, with our writer: `mcap_conformance_writer VARIANT.json` writes the
//! variant's file to stdout, as the suite's runners expect of a writer, for a comparison with the suite's expected
//! `VARIANT.mcap` beside it (docs/src/explanations/architecture.md, "Written by hand, held to others' tests").
//! A variant asking for what the writer does not do exits with status 3 and says so; a file that is not a variant,
//! status 1.

mod variant;

use std::io::Write;
use std::process::ExitCode;
use variant::Refusal;

fn main() -> ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!(
            "usage: mcap_conformance_writer VARIANT.json (a writer variant of foxglove/mcap's tests/conformance)"
        );
        return ExitCode::from(2);
    };
    let written = std::fs::read_to_string(&path)
        .map_err(|e| Refusal::Invalid(format!("cannot be read: {e}")))
        .and_then(|json| variant::parse(&json))
        .and_then(|v| variant::write(&v));
    match written {
        Ok(bytes) => match std::io::stdout().lock().write_all(&bytes) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("{path}: writing the file to stdout failed: {e}");
                ExitCode::from(1)
            }
        },
        Err(Refusal::Unsupported(why)) => {
            eprintln!("{path}: unsupported: {why}");
            ExitCode::from(3)
        }
        Err(Refusal::Invalid(why)) => {
            eprintln!("{path}: not a writer variant of the MCAP conformance suite: {why}");
            ExitCode::from(1)
        }
    }
}
