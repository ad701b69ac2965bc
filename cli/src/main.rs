//! The `critterbox` command: parses arguments, runs, and maps the outcome to an exit code:
//! 0 ok, 1 an error or a difference (a replay that departs from its recording, two recordings
//! that differ, a failed test), 2 bad arguments (clap), 3 a recording that is damaged or cut
//! off (whatever could be read was used and printed first).

mod commands;
mod plot;

use clap::Parser;
use std::io::Write;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = commands::Cli::parse();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let result = commands::execute(cli, &mut out).and_then(|()| Ok(out.flush()?));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A closed pipe (`critterbox run | head`) is the reader's choice, not a failure.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            let _ = out.flush(); // what was printed comes before the error
            eprintln!("error: {e:#}");
            if let Some(i) = e.downcast_ref::<commands::record::Interrupted>() {
                // 128 + the signal, as a shell reports a process the signal ended.
                ExitCode::from(i.exit_code())
            } else if let Some(i) = e.downcast_ref::<commands::sweep::Interrupted>() {
                ExitCode::from(i.exit_code())
            } else if is_damaged_data(&e) {
                ExitCode::from(DAMAGED_DATA)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

/// The exit code of a command that read a damaged or cut-off recording.
const DAMAGED_DATA: u8 = 3;

fn is_damaged_data(e: &anyhow::Error) -> bool {
    matches!(
        e.downcast_ref::<critterbox::recording::RecordingError>(),
        Some(critterbox::recording::RecordingError::Damaged { .. })
    )
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
