#!/usr/bin/env bash
# Prepare a machine for mitsuba_brdfs: an LLVM >= 17 runtime for Dr.Jit's LLVM backend,
# and a virtual environment (.venv) with the package and its pinned dependencies.
# Safe to run repeatedly: each step is skipped when it is already done.
#   scripts/bootstrap.sh [extra]   extra = pip extra to install: "dev" (default) or "test",
#   the package with the test tools, the explorer and Debian's chromium; "figures", the
#   package alone (what `make figures` and `make docs` need)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
extra="${1:-dev}"
venv="${MITSUBA_BRDFS_VENV:-$root/.venv}"
python="${PYTHON:-python3}"

say() { printf '[bootstrap] %s\n' "$*"; }

# apt_install PACKAGE...: Debian's packages (sudo when not root)
apt_install() {
  local sudo_cmd=""
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $sudo_cmd apt-get update -qq
  $sudo_cmd apt-get install -y -qq "$@" >/dev/null
}

# --- 1. LLVM runtime ---------------------------------------------------------------------------
# Dr.Jit 1.5 loads the system libLLVM. LLVM <= 16 aborts the process while compiling kernels
# ("LLVM ERROR: Cannot select ... fminimum"), so a release >= 17 must be present.
have_llvm() {
  local d f
  if [ -n "${DRJIT_LIBLLVM_PATH:-}" ] && [ -e "$DRJIT_LIBLLVM_PATH" ]; then return 0; fi
  for d in /usr/lib/x86_64-linux-gnu /usr/lib/aarch64-linux-gnu /usr/lib /usr/local/lib /usr/lib64; do
    for f in "$d"/libLLVM-[0-9]*.so* "$d"/libLLVM.so.[0-9]*; do
      [ -e "$f" ] || continue
      local v; v="$(basename "$f" | sed -E 's/^libLLVM[-.]?(so\.)?([0-9]+).*/\2/')"
      if [ -n "$v" ] && [ "$v" -ge 17 ] 2>/dev/null; then return 0; fi
    done
  done
  return 1
}
if have_llvm; then
  say "LLVM >= 17 runtime found"
else
  say "no LLVM >= 17 runtime found: installing Debian's libllvm19"
  apt_install libllvm19
  have_llvm || { say "libllvm19 installed but not found; set DRJIT_LIBLLVM_PATH"; exit 1; }
fi

# --- 1b. A browser for the explorer's page test (dev and test set-ups) ---------------------------
# tests/test_explore_browser.py drives Debian's chromium headless (Playwright cannot download
# its own browsers here).
if [ "$extra" = "dev" ] || [ "$extra" = "test" ]; then
  if command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1; then
    say "chromium found"
  else
    say "installing Debian's chromium (the explorer's browser test)"
    apt_install chromium
  fi
fi

# --- 2. Virtual environment --------------------------------------------------------------------
if [ ! -x "$venv/bin/python" ]; then
  if ! command -v "$python" >/dev/null 2>&1; then
    say "no $python found: install Python >= 3.9 (Debian: sudo apt-get install python3 python3-venv)"
    exit 1
  fi
  # Debian's python3 leaves venv's pip (ensurepip) to the package python3-venv
  if ! "$python" -m ensurepip --version >/dev/null 2>&1; then
    say "$python cannot create a virtual environment: install Debian's python3-venv (sudo apt-get install python3-venv), then run this again"
    exit 1
  fi
  say "creating virtual environment $venv"
  "$python" -m venv "$venv"
fi
want="$(cat "$root/pyproject.toml" | sha256sum | cut -c1-16)"
stamp="$venv/.mitsuba_brdfs-$extra.stamp"
# an extra that includes this one will do: dev and test hold everything figures needs
case "$extra" in
  figures) covers="figures test dev" ;;
  *) covers="$extra" ;;
esac
current=""
for e in $covers; do
  if [ -f "$venv/.mitsuba_brdfs-$e.stamp" ] && [ "$(cat "$venv/.mitsuba_brdfs-$e.stamp")" = "$want" ]; then
    current="$e"
  fi
done
if [ -n "$current" ]; then
  say "virtual environment up to date"
else
  say "installing mitsuba_brdfs[$extra] into $venv"
  # -qq: errors only (setuptools' notes on editable installs are not the user's concern);
  # --no-compile: Python compiles the modules a process imports when it first imports them,
  # instead of pip compiling every module of every dependency here (half the install's CPU)
  # pip >= 23 (Python 3.11's own) installs the package as it is; an older one is upgraded
  if ! "$venv/bin/python" -c "import sys, pip; sys.exit(int(pip.__version__.split('.')[0]) < 23)"; then
    "$venv/bin/python" -m pip install -qq --no-compile --upgrade pip
  fi
  "$venv/bin/python" -m pip install -qq --no-compile -e "$root[$extra]"
  echo "$want" > "$stamp"
fi
say "ready: $venv/bin/python"
