//! What can go wrong with a recording: reading it, writing it, rebuilding its scene, replaying,
//! exporting and recovering it.
//!
//! A variant that wraps the error it was caused by (the world's, an I/O or an MCAP error)
//! returns it from `source()` and does not repeat it in its own message, so a chain printed as
//! anyhow's `{:#}` prints (each link joined by ": ") says everything once. `with_causes`
//! prints that chain inside the library.

use std::path::PathBuf;

/// Everything that can go wrong with a recording.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {message}")]
    CannotRead {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// Not an MCAP file.
    #[error("{path} is not an MCAP file (it does not start with the MCAP magic bytes)")]
    NotMcap {
        /// The file.
        path: PathBuf,
    },
    /// Part of the file could not be read (damaged or cut off); what could be read was used.
    #[error("{path} is damaged or incomplete: {what}")]
    Damaged {
        /// The file.
        path: PathBuf,
        /// Which steps are missing and why.
        what: String,
    },
    /// An MCAP file, but not one critterbox wrote.
    #[error("{path} is an MCAP file but not a critterbox recording: {reason}")]
    NotCritterbox {
        /// The file.
        path: PathBuf,
        /// What is missing.
        reason: String,
    },
    /// A message whose JSON does not decode.
    #[error("a {topic} message is not valid: {error}")]
    BadMessage {
        /// The message's topic.
        topic: String,
        /// What the decoder found.
        error: serde_json::Error,
    },
    /// A hash message whose hash is not hexadecimal.
    #[error("a {topic} message has a bad hash '{hash}'")]
    BadHash {
        /// The message's topic.
        topic: String,
        /// The hash as written.
        hash: String,
    },
    /// `inspect --critter ID` named a critter the recording does not hold.
    #[error("critter {critter} is not in {path}: no full state, collision or lifecycle event names it ({hint}); give an id as `inspect` and `replay --step` print them")]
    NoSuchCritter {
        /// The file.
        path: PathBuf,
        /// The critter asked for, as ids print.
        critter: String,
        /// The ids the file has near it.
        hint: String,
    },
    /// A recorded full state whose columns do not fit together.
    #[error("the state of step {step}: {reason}")]
    BadState {
        /// The state's step.
        step: u64,
        /// What does not fit.
        reason: String,
    },
    /// The file's hashes were computed by another version of the state hash.
    #[error(
        "{path}: its state hashes were computed by state hash version {theirs}, and this \
         critterbox computes version {ours}, so they cannot be checked; record the run again \
         with this critterbox"
    )]
    OtherStateHash {
        /// The file.
        path: PathBuf,
        /// The file's version.
        theirs: String,
        /// This critterbox's version.
        ours: &'static str,
    },
    /// The recording could not be written.
    #[error("cannot write the recording {path}: {message}")]
    CannotWrite {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// An output file or folder could not be created.
    #[error("cannot create {path}: {error}")]
    CannotCreate {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// A rewrite's output is its input.
    #[error("the output {path} would overwrite the input")]
    WouldOverwrite {
        /// The output.
        path: PathBuf,
    },
    /// The recorded built-in scene could not be built again.
    #[error("rebuilding the built-in scene '{scene}' (recorded by critterbox {version})")]
    Builtin {
        /// The scene.
        scene: String,
        /// The critterbox that recorded it.
        version: String,
        /// Why.
        #[source]
        error: Box<crate::Error>,
    },
    /// The recorded script scene could not be loaded from the attachments.
    #[error("rebuilding the script scene '{scene}' from the recording's attachments")]
    ScriptScene {
        /// The scene.
        scene: String,
        /// Why.
        #[source]
        error: Box<crate::Error>,
    },
    /// The recorded world was built by a test function, not by a scene.
    #[error(
        "the world of this recording was built by the test {case} (critterbox test recorded it \
         when the test failed), not by a scene, so it cannot be rebuilt to verify: replay it \
         without --verify, or run the test again with `critterbox test FILE --filter NAME`"
    )]
    BuiltByTest {
        /// The test.
        case: String,
    },
    /// The scene script named in the metadata is not attached.
    #[error(
        "the recording has no attachment '{file}' (the scene script); it cannot be re-simulated"
    )]
    NoSceneScript {
        /// The script's name.
        file: String,
    },
    /// The folder the recorded scripts are written into could not be made.
    #[error("making a temporary folder for the recorded scripts")]
    TempFolder(#[source] std::io::Error),
    /// The recorded method is not one this critterbox knows.
    #[error("the recording's method '{method}': {reason}")]
    Method {
        /// The method as recorded.
        method: String,
        /// Why it does not parse.
        reason: String,
    },
    /// A step asked for after the recording's last.
    #[error("the recording ends at step {last}; there is no step {step}")]
    NoStep {
        /// The step asked for.
        step: u64,
        /// The last step recorded.
        last: u64,
    },
    /// A re-simulated step failed.
    #[error("the replay failed at step {step}: {error}")]
    StepFailed {
        /// Steps completed before the failure.
        step: u64,
        /// The step's error.
        error: crate::Error,
    },
    /// A recorded reload could not be made again.
    #[error("the reload of {file} after step {step} could not be made again: {reason}")]
    Reload {
        /// Steps taken when the kind file was reloaded.
        step: u64,
        /// The kind file.
        file: String,
        /// Why not.
        reason: String,
    },
    /// The scene asked to stop before the step a replay was to reach.
    #[error("the scene stopped after step {step} ({reason})")]
    SceneStopped {
        /// Steps taken.
        step: u64,
        /// The scene's reason.
        reason: String,
    },
    /// A replayed step's hash is not the recorded one.
    #[error(
        "the replay diverged from the recording at step {step} (hash {got:016x}, recorded \
         {recorded:016x}); step {shown} cannot be shown exactly: run `critterbox replay --verify`"
    )]
    Diverged {
        /// The first step that differs.
        step: u64,
        /// The replayed hash.
        got: u64,
        /// The recorded hash.
        recorded: u64,
        /// The step that was to be shown.
        shown: u64,
    },
    /// A replay from step 0 reached a recorded full state and differs from it.
    #[error("the replay differs from the keyframe at step {step}: {difference}")]
    DiffersFromKeyframe {
        /// The full state's step.
        step: u64,
        /// The first difference.
        difference: String,
    },
    /// A recorded full state could not be restored.
    #[error("cannot start from the state at step {step}: {reason}")]
    CannotRestore {
        /// The full state's step.
        step: u64,
        /// Why.
        reason: String,
    },
    /// A restored world has no recorded hash to be checked against.
    #[error("no recorded hash at step {step} to check the restored world against")]
    NoHashToCheck {
        /// The restored step.
        step: u64,
    },
    /// A restored world's hash is not the recorded one.
    #[error("the restored world is not the recorded one")]
    RestoredDiffers(#[source] Box<RecordingError>),
    /// `export --every-step`'s replay departed from the recording.
    #[error(
        "the replay diverged from the recording at step {step}; run `critterbox replay \
         --verify` (the states written so far are exact)"
    )]
    ExportDiverged {
        /// The first step that differs.
        step: u64,
    },
    /// The rebuilt world refused a recorded setting.
    #[error(transparent)]
    World(#[from] crate::Error),
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The MCAP writer failed.
    #[error(transparent)]
    Mcap(#[from] mcap::McapError),
}

/// `e` and its causes, each joined to the next by ": " (as the CLI prints an error).
pub(crate) fn with_causes(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text.push_str(": ");
        text.push_str(&c.to_string());
        cause = c.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error as _;
    use std::io::ErrorKind;

    /// Whether an `io::Error` of `kind` is a link of `e`'s chain (as the CLI looks for a broken
    /// pipe).
    fn has_io(e: &RecordingError, kind: ErrorKind) -> bool {
        let mut link: Option<&(dyn std::error::Error + 'static)> = Some(e);
        while let Some(l) = link {
            if l.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == kind)
            {
                return true;
            }
            link = l.source();
        }
        false
    }

    #[test]
    fn a_rebuild_error_says_what_was_rebuilt_then_why() {
        let e = RecordingError::Builtin {
            scene: "gas".into(),
            version: "0.1.0".into(),
            error: Box::new(crate::Error::UnknownScene {
                name: "gas".into(),
                known: "pegs".into(),
            }),
        };
        assert_eq!(
            with_causes(&e),
            "rebuilding the built-in scene 'gas' (recorded by critterbox 0.1.0): unknown scene \
             'gas' (built-in scenes: pegs; `critterbox run --list` describes them)"
        );
    }

    #[test]
    fn io_errors_stay_in_the_chain_and_are_said_once() {
        let e = RecordingError::TempFolder(ErrorKind::PermissionDenied.into());
        assert!(has_io(&e, ErrorKind::PermissionDenied));
        assert_eq!(
            with_causes(&e),
            "making a temporary folder for the recorded scripts: permission denied"
        );
        let e = RecordingError::from(mcap::McapError::from(std::io::Error::from(
            ErrorKind::BrokenPipe,
        )));
        assert!(has_io(&e, ErrorKind::BrokenPipe));
        assert_eq!(
            with_causes(&e),
            "I/O error from writing, or reading a compression stream: broken pipe"
        );
    }

    #[test]
    fn a_restore_that_differs_says_how() {
        let e =
            RecordingError::RestoredDiffers(Box::new(RecordingError::NoStep { step: 9, last: 4 }));
        assert!(e.source().is_some());
        assert_eq!(
            with_causes(&e),
            "the restored world is not the recorded one: the recording ends at step 4; there is \
             no step 9"
        );
    }
}
