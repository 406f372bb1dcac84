#!/usr/bin/env bash
# Sets everything up on a fresh machine and runs a job.
#   bash scripts/bootstrap.sh test        -> all tests
#   bash scripts/bootstrap.sh reproduce   -> the main job (the paper's experiments, simulated)
#   bash scripts/bootstrap.sh detect      -> slipreflex detect on the shipped example recording
#   bash scripts/bootstrap.sh study       -> the parameter study over plausible plants
#
# Works on a stock Debian 12 / Ubuntu 24.04 whose python3 is the distribution's and
# refuses `pip install` outside a virtual environment (PEP 668): everything Python goes
# into the project's own virtual environment, .venv (activate it afterwards with
# `source .venv/bin/activate`). Debian packages (the AVR toolchain, simavr, avrdude,
# python3-venv) are installed with apt-get, as root or through sudo.
set -euo pipefail
cd "$(dirname "$0")/.."
job="${1:-test}"; shift || true
case "$job" in
  test|reproduce|detect|study) ;;
  *) echo "bootstrap.sh: unknown job '$job' (use test, reproduce, detect or study)" >&2; exit 2 ;;
esac

PYTHON="${PYTHON:-python3}"
command -v "$PYTHON" >/dev/null 2>&1 || { echo "bootstrap.sh: no '$PYTHON' on PATH (install python3 >= 3.11)" >&2; exit 2; }

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
  if ! command -v apt-get >/dev/null 2>&1; then
    echo "bootstrap.sh: missing system packages (${need_apt[*]}) and no apt-get to install them" >&2; exit 2
  fi
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "bootstrap.sh: installing Debian packages: ${need_apt[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_apt[@]}" >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  echo "bootstrap.sh: creating the project's virtual environment in .venv"
  "$PYTHON" -m venv .venv
fi
VPY=.venv/bin/python
# Inside a venv pip neither needs root nor warns about it.
"$VPY" -m pip install -q --disable-pip-version-check --upgrade pip >/dev/null
"$VPY" -m pip install -q --disable-pip-version-check -e ".[test]"
export PATH="$PWD/.venv/bin:$PATH"

case "$job" in
  test) exec "$VPY" -m pytest -q "$@" ;;
  reproduce) exec slipreflex reproduce "$@" ;;
  detect) exec slipreflex detect examples/slip_example.csv "$@" ;;
  study) exec slipreflex study "$@" ;;
esac
