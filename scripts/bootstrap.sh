#!/usr/bin/env bash
# Sets everything up on a fresh machine (Python 3.11 + pip, root for apt) and runs a job.
#   bash scripts/bootstrap.sh test        -> all tests
#   bash scripts/bootstrap.sh reproduce   -> the main job (the paper's experiments, simulated)
#   bash scripts/bootstrap.sh detect      -> slipreflex detect on the shipped example recording
set -euo pipefail
cd "$(dirname "$0")/.."
job="${1:-test}"; shift || true

need_apt=()
for pkg in gcc-avr avr-libc simavr libsimavr-dev libelf-dev pkg-config make gcc libc6-dev; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_apt+=("$pkg")
done
if [ ${#need_apt[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_apt[@]}" >/dev/null
fi

python3 -m pip install -q --disable-pip-version-check -e ".[test]"

case "$job" in
  test) exec python3 -m pytest -q "$@" ;;
  reproduce) exec slipreflex reproduce "$@" ;;
  detect) exec slipreflex detect examples/slip_example.csv --out out/detect/slip_example "$@" ;;
  *) echo "bootstrap.sh: unknown job '$job' (use test, reproduce or detect)" >&2; exit 2 ;;
esac
