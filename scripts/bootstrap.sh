#!/usr/bin/env bash
# Sets everything up on a fresh machine and runs a job.
#   bash scripts/bootstrap.sh test        -> all tests
#   bash scripts/bootstrap.sh reproduce   -> the main job (the paper's experiments, simulated)
#   bash scripts/bootstrap.sh detect      -> slipreflex detect on the shipped example recording
#   bash scripts/bootstrap.sh study       -> the parameter study over plausible plants
# Arguments after the job go to it (`bash scripts/bootstrap.sh reproduce --trials 3`).
#
# Works on a stock Debian 12 / Ubuntu 24.04 whose python3 is the distribution's and
# refuses `pip install` outside a virtual environment (PEP 668), and on a machine with a
# user-installed Python: everything Python goes into the project's own virtual
# environment, .venv (activate it afterwards with `source .venv/bin/activate`). pip never
# runs outside it, so it neither needs root nor warns about it. Debian packages (the AVR
# toolchain, simavr, avrdude for `make -C firmware flash`, python3-venv) are installed
# with apt-get, as root or through sudo. PYTHON=/path/to/python3 picks the interpreter.
# tests/test_bootstrap.py runs this script against a system Python made externally
# managed; scripts/dev/fresh_debian_check.sh runs it in a freshly debootstrapped Debian 12.
set -euo pipefail
cd "$(dirname "$0")/.."
job="${1:-test}"; shift || true
case "$job" in
  test|reproduce|detect|study) ;;
  *) echo "bootstrap.sh: unknown job '$job' (use test, reproduce, detect or study)" >&2; exit 2 ;;
esac

PYTHON="${PYTHON:-python3}"
command -v "$PYTHON" >/dev/null 2>&1 || { echo "bootstrap.sh: no '$PYTHON' on PATH (install python3 >= 3.11)" >&2; exit 2; }
"$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 11))' \
  || { echo "bootstrap.sh: $("$PYTHON" --version 2>&1) is too old (slipreflex needs Python >= 3.11; set PYTHON=...)" >&2; exit 2; }

need_apt=()
for pkg in gcc-avr avr-libc simavr libsimavr-dev libelf-dev pkg-config make gcc libc6-dev avrdude; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_apt+=("$pkg")
done
# A distribution Python without ensurepip cannot make a venv: python3-venv provides it.
if [ ! -x .venv/bin/python ] && ! "$PYTHON" -c "import ensurepip, venv" >/dev/null 2>&1; then
  ver=$("$PYTHON" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')
  need_apt+=("python3-venv" "python${ver}-venv")
fi
if [ ${#need_apt[@]} -gt 0 ]; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null 2>&1 || {
      echo "bootstrap.sh: missing Debian packages; as root run: apt-get install ${need_apt[*]}" >&2; exit 2; }
    SUDO="sudo"
  fi
  command -v apt-get >/dev/null 2>&1 || {
    echo "bootstrap.sh: missing system packages (${need_apt[*]}) and no apt-get to install them" >&2; exit 2; }
  echo "bootstrap.sh: installing Debian packages: ${need_apt[*]}"
  # apt's chatter (debconf notes, progress) goes to a log, shown only when apt fails.
  aptlog=$(mktemp)
  if ! { $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_apt[@]}"; } >"$aptlog" 2>&1; then
    cat "$aptlog" >&2; rm -f "$aptlog"
    echo "bootstrap.sh: apt-get could not install: ${need_apt[*]}" >&2; exit 2
  fi
  rm -f "$aptlog"
fi

if [ ! -x .venv/bin/python ]; then
  echo "bootstrap.sh: creating the project's virtual environment in .venv (from $(command -v "$PYTHON"))"
  "$PYTHON" -m venv .venv
fi
VPY=.venv/bin/python
# Every extra pyproject.toml declares (test, study, dev, ...), read from it so a new extra needs no edit here.
extras=$("$VPY" -c 'import tomllib; t = tomllib.load(open("pyproject.toml", "rb")); print(",".join(t.get("project", {}).get("optional-dependencies", {})))')
# pip's own lines (Collecting / Downloading / Installing ...) show the progress: on a fresh
# machine this step downloads the dependencies and takes a minute or two; it is never silent.
echo "bootstrap.sh: installing slipreflex and its dependencies into .venv with pip (a minute or two on a fresh machine)"
"$VPY" -m pip install --disable-pip-version-check --progress-bar on -e ".${extras:+[$extras]}"
echo "bootstrap.sh: slipreflex is installed in .venv; to use it later: source .venv/bin/activate"
export PATH="$PWD/.venv/bin:$PATH"

case "$job" in
  # The Debian packages above are installed, so a firmware test that cannot find its tools fails.
  # Every test: the suite on every core (pytest-xdist), then the real-time tests alone, so their
  # deadlines measure the loop, not the other tests. Arguments replace both with one pytest run.
  test)
    export SLIPREFLEX_REQUIRE_TOOLS=1
    if [ "$#" -gt 0 ]; then exec "$VPY" -m pytest -q "$@"; fi
    "$VPY" -m pytest -q -n auto -m "not realtime"
    exec "$VPY" -m pytest -q -m realtime ;;
  reproduce) exec slipreflex reproduce "$@" ;;
  detect) exec slipreflex detect examples/slip_example.csv "$@" ;;
  study) exec slipreflex study "$@" ;;
esac
