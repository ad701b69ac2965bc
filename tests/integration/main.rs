//! The library's integration tests, one binary (`cargo test --test integration`): each file of
//! this folder is a module, named for what it guards, and the shared helpers are modules too.
//! One binary links once; a test file per binary would link the library once per file.
//! `tests/script_tests.rs` (the rhai script tests) is a binary of its own: it has its own
//! harness and changes the process's working directory.

// Shared helpers.
mod common;
mod fuzz_harness;
mod script_common;

// The tests, by what they guard.
mod auto_bullets;
mod auto_islands;
mod bad_input;
mod broad_phase;
mod collisions;
mod determinism;
mod fuzz_recording;
mod fuzz_scene;
mod hook_calls;
mod layers;
mod lifecycle;
mod locality;
mod methods;
mod mixed_scenes;
mod parallel;
mod reliability;
mod reload;
mod roles;
mod script_errors;
mod script_limits;
mod scripts;
mod sleep;
mod solve;
mod spawning;
mod touch;
mod walls;
