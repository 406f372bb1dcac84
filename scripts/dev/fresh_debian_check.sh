#!/usr/bin/env bash
# Runs the README's set-up on a stock Debian 12 whose python3 is externally managed
# (PEP 668), the way a new user meets it: debootstraps a minimal bookworm into a folder,
# installs only `python3` there (no pip, no venv module, no compiler), copies the
# committed tree (git archive HEAD) to /src and runs, with a clean environment, as root:
#     bash scripts/bootstrap.sh JOB        (default JOB: test)
#     make -C firmware flash PORT=...      (against a stand-in Arduino bootloader)
#
# Needs root, debootstrap (apt-get install debootstrap) and network access to Debian and
# PyPI; takes 3-5 minutes. Not part of CI (tests/test_bootstrap.py is its fast part).
#   sudo bash scripts/dev/fresh_debian_check.sh [JOB] [DIR]      (DIR default: /tmp/slipreflex-deb12)
# If pip on this machine needs a CA bundle (PIP_CERT), that file is handed to the chroot.
set -euo pipefail
cd "$(dirname "$0")/.."
job="${1:-test}"
root="${2:-/tmp/slipreflex-deb12}"
[ "$(id -u)" -eq 0 ] || { echo "fresh_debian_check.sh: needs root (debootstrap, chroot)" >&2; exit 2; }
command -v debootstrap >/dev/null || { echo "fresh_debian_check.sh: apt-get install debootstrap" >&2; exit 2; }

cleanup() { for m in dev/pts dev proc sys; do umount -l "$root/$m" 2>/dev/null || true; done; }
trap cleanup EXIT
if [ ! -x "$root/usr/bin/apt-get" ]; then
  echo "== debootstrap bookworm (minbase) into $root"
  debootstrap --variant=minbase bookworm "$root" http://deb.debian.org/debian >"$root.debootstrap.log" 2>&1
fi
mount -t proc proc "$root/proc"; mount --rbind /sys "$root/sys"; mount --rbind /dev "$root/dev"
cp /etc/resolv.conf "$root/etc/resolv.conf"
certenv=()
if [ -n "${PIP_CERT:-}" ] && [ -f "$PIP_CERT" ]; then
  cp "$PIP_CERT" "$root/root/pip-ca.crt"; certenv=(PIP_CERT=/root/pip-ca.crt)
fi
inchroot() { chroot "$root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LANG=C.UTF-8 \
  "${certenv[@]}" bash -c "$1"; }

echo "== the stock system: python3 only"
inchroot "apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3 >/dev/null 2>&1
  python3 --version; ls /usr/lib/python3*/EXTERNALLY-MANAGED
  python3 -m pip --version 2>&1 | tail -1; python3 -c 'import ensurepip' 2>&1 | tail -1"

rm -rf "$root/src"; mkdir "$root/src"; git archive HEAD | tar -x -C "$root/src"
echo "== bash scripts/bootstrap.sh $job   (in the chroot, clean environment)"
inchroot "cd /src && time bash scripts/bootstrap.sh $job"

echo "== make -C firmware flash, against a stand-in bootloader on a pseudo-terminal"
inchroot "cd /src && .venv/bin/python tests/stk500_standin.py --check firmware/build/daq.hex -- make -C firmware flash"
