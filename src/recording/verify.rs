//! `replay --verify`: re-simulate a recorded run from the file alone and check every step's
//! hash, totals and events, and every recorded full state, bit for bit.

use super::capture;
use super::compare::{first_difference, same_json};
use super::error::{with_causes, RecordingError};
use super::reader::{decode, decode_state, read_items, Flow, Item, Recording};
use super::replay::Replay;
use super::schema::{self, CollisionsMsg, ErrorMsg, HashMsg, LifecycleMsg, LogMsg};

/// The first place a replay departs from its recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Mismatch {
    /// The step.
    pub step: u64,
    /// What differs there.
    pub what: String,
    /// The first critter that differs, at `critter_step` (the nearest recorded full state at or
    /// after `step`), if one was found.
    pub critter: Option<(u64, String)>,
}

/// What a verification found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VerifyReport {
    /// Steps re-simulated.
    pub steps: u64,
    /// Hashes compared.
    pub hashes: u64,
    /// Full states compared.
    pub states: u64,
    /// Event messages (collisions, lifecycle, log) compared.
    pub events: u64,
    /// The first mismatch, if any.
    pub mismatch: Option<Mismatch>,
    /// The recorded error, reproduced at this step.
    pub error_reproduced: Option<u64>,
    /// Why the file's readable part ends early, for a cut-off file.
    pub truncated: Option<String>,
}

impl VerifyReport {
    /// True when nothing differed.
    pub fn passed(&self) -> bool {
        self.mismatch.is_none()
    }
}

#[derive(serde::Deserialize)]
struct StepOnly {
    step: u64,
}

/// Re-simulates `rec` and compares everything it recorded. `progress` gets the step reached.
pub fn verify(
    rec: &Recording,
    mut progress: impl FnMut(u64),
) -> Result<VerifyReport, RecordingError> {
    rec.check_state_hash()?;
    let mut replay = Replay::new(rec)?;
    let mut report = VerifyReport {
        truncated: rec.truncated.clone(),
        ..VerifyReport::default()
    };
    let mut done = false;
    let format_1 = rec.format_version() < 2;
    let end = read_items(&rec.path, |item| {
        let Item::Message { topic, data, .. } = item else {
            return Ok(Flow::Continue);
        };
        if topic == schema::SCENE || done {
            return Ok(Flow::Continue);
        }
        let step = decode::<StepOnly>(topic, data)?.step;
        // Every step from 0 has a hash (the error comes one after the last), read or lost in a
        // damaged stretch: a step past their count is damage, not steps to re-simulate.
        let recorded = steps_held(rec);
        if step > recorded && report.mismatch.is_none() {
            report.mismatch = Some(Mismatch {
                step: replay.step_count(),
                what: format!(
                    "a {topic} message names step {step}, but the file holds the hashes of \
                     {recorded} steps: the file is damaged"
                ),
                critter: None,
            });
            done = true;
            return Ok(Flow::Stop);
        }
        // After a mismatch, only look for the next full state, to name the critter.
        let looking = report.mismatch.is_some();
        if looking && topic != schema::STATE {
            return Ok(Flow::Continue);
        }
        if topic == schema::ERROR {
            let e: ErrorMsg = decode(topic, data)?;
            let before = e.step.saturating_sub(1);
            let reached: Result<(), RecordingError> = replay.step_to(before, |_| Ok(()));
            if let Err(err) = reached {
                report.mismatch = Some(Mismatch {
                    step: replay.step_count(),
                    what: with_causes(&err),
                    critter: None,
                });
                done = true;
                return Ok(Flow::Stop);
            }
            match replay.step_expecting_error() {
                Some(_) => report.error_reproduced = Some(e.step),
                None => {
                    report.mismatch = Some(Mismatch {
                        step: e.step,
                        what: format!(
                            "the recorded run failed in step {} ({}), the replay did not",
                            e.step, e.message
                        ),
                        critter: None,
                    })
                }
            }
            done = true;
            return Ok(Flow::Stop);
        }
        let reached: Result<(), RecordingError> = replay.step_to(step, |w| {
            progress(w.step_count());
            Ok(())
        });
        if let Err(err) = reached {
            if looking {
                done = true;
                return Ok(Flow::Stop);
            }
            report.mismatch = Some(Mismatch {
                step: replay.step_count(),
                what: format!(
                    "{}, but the recording goes on to step {step}",
                    with_causes(&err)
                ),
                critter: None,
            });
            done = true;
            return Ok(Flow::Stop);
        }
        report.steps = replay.step_count();
        let world = replay.world();
        let differs: Option<String> = match topic {
            schema::HASH => {
                report.hashes += 1;
                let m: HashMsg = decode(topic, data)?;
                let got = format!("{:016x}", world.state_hash());
                (got != m.hash).then(|| format!("state hash recorded {}, replayed {got}", m.hash))
            }
            schema::TOTALS => {
                let recorded: schema::TotalsMsg = decode(topic, data)?;
                let (_, mine) = capture::any_hash_and_totals(world);
                (!same_json(&recorded, &mine)).then(|| {
                    format!(
                        "totals recorded {}, replayed {}",
                        serde_json::to_string(&recorded).unwrap_or_default(),
                        serde_json::to_string(&mine).unwrap_or_default()
                    )
                })
            }
            schema::STATE => {
                report.states += 1;
                let recorded = decode_state(data)?;
                let mine = capture::any_state(world);
                let diff = first_difference(&recorded, &mine, "recorded", "replayed");
                if let Some(m) = &mut report.mismatch {
                    m.critter = diff.map(|d| (step, d));
                    done = true;
                    return Ok(Flow::Stop);
                }
                diff.map(|d| format!("full state differs: {d}"))
            }
            schema::COLLISIONS | schema::LIFECYCLE | schema::LOG => {
                report.events += 1;
                let (c, l, g) = capture::any_events(world);
                // A format 1 file kept less of each step's lifecycle: compare that much.
                let l = if format_1 {
                    l.and_then(|l| l.format_1_view())
                } else {
                    l
                };
                let same = match topic {
                    schema::COLLISIONS => c.is_some_and(|c| {
                        same_json(&decode::<CollisionsMsg>(topic, data).ok(), &Some(c))
                    }),
                    schema::LIFECYCLE => l.is_some_and(|l| {
                        same_json(&decode::<LifecycleMsg>(topic, data).ok(), &Some(l))
                    }),
                    _ => {
                        g.is_some_and(|g| same_json(&decode::<LogMsg>(topic, data).ok(), &Some(g)))
                    }
                };
                (!same).then(|| format!("the {topic} message differs"))
            }
            _ => None,
        };
        if let Some(what) = differs {
            // The first critter that differs: here if this step has a full state, else at the
            // next one (the reader goes on looking).
            let critter = if topic == schema::STATE {
                Some((
                    step,
                    what.trim_start_matches("full state differs: ").to_string(),
                ))
            } else {
                None
            };
            let found = critter.is_some();
            report.mismatch = Some(Mismatch {
                step,
                what,
                critter,
            });
            if found {
                done = true;
                return Ok(Flow::Stop);
            }
        }
        Ok(Flow::Continue)
    })?;
    if report.truncated.is_none() {
        report.truncated = end.truncated;
    }
    // Events recorded nowhere but present in the replay are not checked message by message;
    // the hashes and totals of every step cover the state they lead to.
    Ok(report)
}

/// How many steps the file held: the hashes read, and those the damaged stretches lost. A
/// stretch is counted by the steps between the hashes around it, but never as more steps than
/// the bytes it skipped (a step's hash message takes several), so a damaged step number
/// cannot make verify re-simulate without end.
fn steps_held(rec: &Recording) -> u64 {
    let lost: u64 = rec
        .gaps
        .iter()
        .map(|g| match g.missing() {
            Some((first, Some(last))) => (last - first + 1).min(g.damage.skipped),
            Some((_, None)) | None => 0,
        })
        .sum();
    rec.hashes.len() as u64 + lost
}
