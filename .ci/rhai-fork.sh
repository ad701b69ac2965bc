#!/usr/bin/env bash
# vendor/rhai against its patch series: rhai as published on crates.io, with
# vendor/rhai/patches/*.patch applied in order, must be vendor/rhai byte for byte (its PATCH.md
# and patches/ aside). Fast: a cargo fetch, an unpack, the patches and a diff; nothing is built.
# Needs cargo (with access to crates.io, or the crate already in cargo's cache), git, tar,
# sha256sum and diff.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

RHAI_VERSION=1.27.0
# The published rhai-1.27.0.crate (crates.io's checksum, as cargo writes it in a Cargo.lock).
RHAI_SHA256=c3925b784c0bee6542637e425ed7511a63257bf11b7ecf51ffd845e2d24d9163
FORK=vendor/rhai
PATCHES=$FORK/patches

fail() {
  echo "rhai-fork: FAILED: $*" >&2
  exit 1
}

for tool in cargo git tar sha256sum diff; do
  command -v "$tool" >/dev/null 2>&1 || fail "'$tool' is not installed"
done
[ -f "$FORK/Cargo.toml" ] || fail "$FORK/Cargo.toml not found (run from a critterbox checkout)"

shopt -s nullglob
patches=("$PATCHES"/[0-9][0-9][0-9][0-9]-*.patch)
shopt -u nullglob
[ "${#patches[@]}" -gt 0 ] || fail "no patches in $PATCHES (NNNN-name.patch)"

work=$(mktemp -d "${TMPDIR:-/tmp}/rhai-fork.XXXXXX")
trap 'rm -rf "$work"' EXIT

# 1. The pristine crate, through cargo: a throwaway package that depends on it and nothing else,
#    outside this workspace (so its [patch.crates-io] does not apply).
mkdir -p "$work/fetch/src"
cat >"$work/fetch/Cargo.toml" <<EOF
[package]
name = "rhai-fork-check"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
rhai = "=$RHAI_VERSION"

[workspace]
EOF
: >"$work/fetch/src/lib.rs"
echo "rhai-fork: fetching rhai $RHAI_VERSION with cargo"
(cd "$work/fetch" && cargo fetch --quiet) ||
  fail "cargo could not fetch rhai $RHAI_VERSION (is crates.io reachable?)"

cargo_home=${CARGO_HOME:-$HOME/.cargo}
crate=
for candidate in "$cargo_home"/registry/cache/*/"rhai-$RHAI_VERSION.crate"; do
  [ -f "$candidate" ] || continue
  sum=$(sha256sum "$candidate") || fail "could not read $candidate"
  if [ "${sum%% *}" = "$RHAI_SHA256" ]; then
    crate=$candidate
    break
  fi
  echo "rhai-fork: skipping $candidate: its sha256 is ${sum%% *}, not $RHAI_SHA256" >&2
done
[ -n "$crate" ] ||
  fail "no rhai-$RHAI_VERSION.crate with sha256 $RHAI_SHA256 under $cargo_home/registry/cache after cargo fetch"

mkdir "$work/crate"
tar -xzf "$crate" -C "$work/crate" || fail "could not unpack $crate"
tree=$work/crate/rhai-$RHAI_VERSION
[ -f "$tree/Cargo.toml" ] || fail "$crate did not unpack to rhai-$RHAI_VERSION/"

# 2. The series, in order. git apply applies a patch whole or not at all, with no fuzz. The
#    sources have CRLF line endings: the settings below keep every byte as the patch has it,
#    whatever the user's git configuration says. The ceiling keeps git from taking a repository
#    around the temporary folder for this one.
for p in "${patches[@]}"; do
  name=${p##*/}
  if ! out=$(cd "$tree" && env -u GIT_DIR -u GIT_WORK_TREE -u GIT_INDEX_FILE \
    GIT_CEILING_DIRECTORIES="$work" \
    git -c core.autocrlf=false -c core.safecrlf=false -c apply.whitespace=nowarn \
    apply -p1 --whitespace=nowarn "$root/$p" 2>&1); then
    echo "$out" >&2
    fail "$name does not apply cleanly to rhai $RHAI_VERSION with the patches before it"
  fi
  echo "rhai-fork: applied $name"
done

# 3. The result against vendor/rhai, all of it but its own PATCH.md and patches/.
mkdir "$work/fork"
cp -R "$FORK/." "$work/fork/" || fail "could not copy $FORK"
rm -rf "$work/fork/PATCH.md" "$work/fork/patches"
if ! diff -r --no-dereference "$tree" "$work/fork" >"$work/diff.txt" 2>&1; then
  sed -e "s|$tree|rhai-$RHAI_VERSION+patches|g" -e "s|$work/fork|$FORK|g" "$work/diff.txt" >"$work/report.txt"
  head -n 200 "$work/report.txt" >&2
  lines=$(wc -l <"$work/report.txt")
  [ "$lines" -le 200 ] || echo "... ($lines lines in all)" >&2
  echo "rhai-fork: (where two lines above look alike, their line endings differ: rhai's sources have CRLF)" >&2
  fail "$FORK is not rhai $RHAI_VERSION with $PATCHES applied (differences above): a change to $FORK needs its patch, and a patch its change (see $FORK/PATCH.md)"
fi
echo "rhai-fork: OK: $FORK is rhai $RHAI_VERSION with its ${#patches[@]} patches, byte for byte"
