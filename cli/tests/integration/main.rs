//! The command's integration tests, one binary (`cargo test -p critterbox-cli --test
//! integration`): each file of this folder is a module, named for what it guards, and the shared
//! helpers are a module too. One binary links once; a test file per binary would link the
//! library once per file. The command runs as a child process (its working directory,
//! environment and signals are the child's), so no test changes what this process shares.

// Shared helpers.
mod common;

// The tests, by what they guard.
mod auto_islands;
mod check;
mod cli;
mod damaged;
mod ids;
mod on_damage;
mod recording;
mod script_state;
mod sets;
mod state_hashes;
mod stops;
mod story;
mod sweep;
mod test_runner;
// Only with the cargo feature `rerun` (the file says so with its own `#![cfg]`).
mod viewer;
mod watch;
