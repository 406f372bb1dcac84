"""``scripts/bootstrap.sh`` on a machine whose ``python3`` is the distribution's (PEP 668).

The script is run for real (bash, ``python3 -m venv``, pip) with ``PATH`` limited to the
system directories, on a copy of it inside a small stand-in project: the stand-in builds
with an in-tree PEP 517 backend and has no dependencies, so pip needs no network and
the test takes seconds. ``dpkg`` and ``apt-get`` are stand-ins that record what they are
asked (the real Debian packages are checked by ``scripts/dev/fresh_debian_check.sh``, which
runs the whole bootstrap in a freshly debootstrapped Debian 12).
"""

import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SYSTEM_PATH = "/usr/sbin:/usr/bin:/sbin:/bin"
SYSTEM_PYTHON = Path("/usr/bin/python3")

BACKEND = '''
"""A PEP 517/660 backend that builds the stand-in package without setuptools."""
import base64, hashlib, os, zipfile

NAME, VERSION = "slipreflex", "0.0.0"
DIST = f"{NAME}-{VERSION}.dist-info"


def _wheel(directory, files):
    name = f"{NAME}-{VERSION}-py3-none-any.whl"
    files[f"{DIST}/METADATA"] = f"Metadata-Version: 2.1\\nName: {NAME}\\nVersion: {VERSION}\\nProvides-Extra: test\\n"
    files[f"{DIST}/WHEEL"] = "Wheel-Version: 1.0\\nGenerator: test\\nRoot-Is-Purelib: true\\nTag: py3-none-any\\n"
    files[f"{DIST}/entry_points.txt"] = "[console_scripts]\\nslipreflex = standin:main\\n"
    record = []
    for path, text in files.items():
        digest = base64.urlsafe_b64encode(hashlib.sha256(text.encode()).digest()).rstrip(b"=").decode()
        record.append(f"{path},sha256={digest},{len(text.encode())}")
    files[f"{DIST}/RECORD"] = "\\n".join(record + [f"{DIST}/RECORD,,"]) + "\\n"
    with zipfile.ZipFile(os.path.join(directory, name), "w") as zf:
        for path, text in files.items():
            zf.writestr(path, text)
    return name


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    with open("src/standin.py") as f:
        return _wheel(wheel_directory, {"standin.py": f.read()})


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    return _wheel(wheel_directory, {"standin.pth": os.path.abspath("src") + "\\n"})
'''

STANDIN = '''
import sys

def main():
    print("standin ran in", sys.prefix, "with", " ".join(sys.argv[1:]))
'''

PYPROJECT = """
[build-system]
requires = []
build-backend = "backend"
backend-path = ["."]
"""


def _script(path: Path, text: str) -> None:
    path.write_text("#!/bin/sh\n" + textwrap.dedent(text))
    path.chmod(path.stat().st_mode | stat.S_IXUSR)


@pytest.fixture
def standin(tmp_path):
    """A project with the real bootstrap.sh, an offline-buildable package and shim tools."""
    proj = tmp_path / "proj"
    (proj / "scripts").mkdir(parents=True)
    (proj / "src").mkdir()
    (proj / "examples").mkdir()
    (proj / "scripts" / "bootstrap.sh").write_bytes((ROOT / "scripts" / "bootstrap.sh").read_bytes())
    (proj / "backend.py").write_text(BACKEND)
    (proj / "src" / "standin.py").write_text(STANDIN)
    (proj / "pyproject.toml").write_text(PYPROJECT)
    (proj / "examples" / "slip_example.csv").write_text("t,x\n0,0\n")
    shims = tmp_path / "shims"
    shims.mkdir()
    log = tmp_path / "apt.log"
    _script(shims / "dpkg", "exit 0\n")                       # every Debian package present
    _script(shims / "apt-get", f'echo "$@" >> {log}\n[ "$1" = install ] && touch {tmp_path}/venv-installed\nexit 0\n')
    return proj, shims, log


def _bootstrap(proj: Path, path: str, *args: str, **env: str) -> subprocess.CompletedProcess:
    environ = {"PATH": path, "HOME": str(proj.parent), "LANG": "C.UTF-8", "PIP_NO_INDEX": "1",
               "PIP_DISABLE_PIP_VERSION_CHECK": "1", **env}
    return subprocess.run(["bash", "scripts/bootstrap.sh", *args], cwd=proj, env=environ,
                          capture_output=True, text=True, timeout=300)


def _externally_managed(python: Path) -> bool:
    stdlib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('stdlib'))"],
                            capture_output=True, text=True, check=True).stdout.strip()
    return (Path(stdlib) / "EXTERNALLY-MANAGED").exists()


requires_system_python = pytest.mark.skipif(
    not SYSTEM_PYTHON.exists(), reason="no distribution python3 in /usr/bin on this machine")


@pytest.mark.slow
@requires_system_python
def test_system_python_is_refused_by_pip_outside_a_venv(tmp_path):
    """The premise: on Debian 12 the distribution's python3 is externally managed."""
    if not _externally_managed(SYSTEM_PYTHON):
        pytest.skip("/usr/bin/python3 is not externally managed here (not a PEP 668 distribution)")
    r = subprocess.run([str(SYSTEM_PYTHON), "-m", "pip", "install", "--dry-run", "--no-index", "x"],
                       capture_output=True, text=True, env={"PATH": SYSTEM_PATH, "HOME": str(tmp_path)})
    assert r.returncode != 0
    assert "externally-managed-environment" in r.stderr or "No module named pip" in r.stderr


@pytest.mark.slow
@requires_system_python
def test_bootstrap_with_the_system_python_makes_and_uses_dot_venv(standin):
    proj, shims, log = standin
    r = _bootstrap(proj, f"{shims}:{SYSTEM_PATH}", "detect", "--method", "dath")
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert "creating the project's virtual environment in .venv (from /usr/bin/python3)" in out
    assert f"standin ran in {proj / '.venv'} with detect examples/slip_example.csv --method dath" in out
    assert "source .venv/bin/activate" in out
    assert "WARNING" not in out and "'root' user" not in out        # no pip "running as root" warning
    assert "externally-managed" not in out
    assert not log.exists()                                          # nothing asked of apt
    cfg = (proj / ".venv" / "pyvenv.cfg").read_text()
    assert "home = /usr/bin" in cfg
    # A second run reuses the venv.
    again = _bootstrap(proj, f"{shims}:{SYSTEM_PATH}", "detect")
    assert again.returncode == 0 and "creating" not in again.stdout + again.stderr


@pytest.mark.slow
@requires_system_python
def test_bootstrap_installs_python3_venv_when_ensurepip_is_missing(standin, tmp_path):
    """Debian's python3 without python3-venv: bootstrap asks apt for it, then makes the venv."""
    proj, shims, log = standin
    version = "import sys; print(f'{sys.version_info[0]}.{sys.version_info[1]}')"
    real = subprocess.run([str(SYSTEM_PYTHON), "-c", version],
                          capture_output=True, text=True, check=True).stdout.strip()
    mark = tmp_path / "venv-installed"
    _script(shims / "python3", f"""
        if [ ! -e {mark} ] && [ "$1" = -c ] && [ "$2" = "import ensurepip, venv" ]; then exit 1; fi
        if [ ! -e {mark} ] && [ "$1" = -m ] && [ "$2" = venv ]; then echo "ensurepip is not available" >&2; exit 1; fi
        exec {SYSTEM_PYTHON} "$@"
        """)
    r = _bootstrap(proj, f"{shims}:{SYSTEM_PATH}", "detect")
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert f"installing Debian packages: python3-venv python{real}-venv" in out
    assert log.read_text().splitlines() == ["update -qq", f"install -y -qq python3-venv python{real}-venv"]
    assert f"standin ran in {proj / '.venv'}" in out


@pytest.mark.slow
def test_bootstrap_with_a_user_installed_python(standin):
    """A Python that is not the distribution's (pyenv, python.org): the venv comes from it."""
    proj, shims, log = standin
    user_python = Path(sys.base_prefix) / "bin" / "python3"
    assert user_python.exists()
    r = _bootstrap(proj, f"{user_python.parent}:{shims}:{SYSTEM_PATH}", "detect")
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert f"(from {user_python})" in out
    assert f"standin ran in {proj / '.venv'}" in out
    assert f"home = {user_python.parent}" in (proj / ".venv" / "pyvenv.cfg").read_text()


@pytest.mark.parametrize("args, env, message", [
    (["frobnicate"], {}, "unknown job 'frobnicate' (use test, reproduce, detect or study)"),
    (["detect"], {"PYTHON": "python-none"}, "no 'python-none' on PATH"),
])
def test_bootstrap_bad_input_is_one_line_exit_2(standin, args, env, message):
    proj, shims, log = standin
    r = _bootstrap(proj, f"{shims}:{SYSTEM_PATH}", *args, **env)
    assert r.returncode == 2
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (proj / ".venv").exists()


@pytest.mark.slow
def test_bootstrap_as_a_user_goes_through_sudo(standin, tmp_path):
    proj, shims, log = standin
    _script(shims / "dpkg", '[ "$2" = avrdude ] && exit 1\nexit 0\n')
    _script(shims / "id", "echo 1000\n")
    _script(shims / "sudo", f'echo "sudo $1" >> {log}\nexec "$@"\n')
    r = _bootstrap(proj, f"{shims}:{SYSTEM_PATH}", "detect")
    assert r.returncode == 0, r.stdout + r.stderr
    assert log.read_text().splitlines() == ["sudo apt-get", "update -qq", "sudo apt-get", "install -y -qq avrdude"]


@pytest.mark.skipif(any(Path(d, "sudo").exists() for d in SYSTEM_PATH.split(":")),
                    reason="this machine has sudo, so the no-sudo path cannot be reached")
def test_bootstrap_without_root_or_sudo_names_the_apt_command(standin, tmp_path):
    """Missing packages, not root, no sudo: the exact command to run, exit 2, no venv yet."""
    proj, shims, log = standin
    _script(shims / "dpkg", '[ "$2" = avrdude ] && exit 1\nexit 0\n')
    _script(shims / "id", "echo 1000\n")
    r = _bootstrap(proj, f"{shims}:{SYSTEM_PATH}", "detect")
    assert r.returncode == 2
    assert "as root run: apt-get install avrdude" in r.stderr
    assert not log.exists() and not (proj / ".venv").exists()


@pytest.mark.slow          # a venv and a pip install (4 s); the fast tier keeps the bad-input checks
@requires_system_python
def test_bootstrap_shows_the_install_as_it_happens(standin):
    """The pip step announces itself and lets pip print its progress (it was silent for a minute)."""
    proj, shims, _ = standin
    r = _bootstrap(proj, f"{shims}:{SYSTEM_PATH}", "detect")
    assert r.returncode == 0, r.stdout + r.stderr
    lines = r.stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("bootstrap.sh: installing slipreflex"))
    pip = [line for line in lines[start + 1:] if line.startswith(("Obtaining", "Processing", "Collecting",
                                                                  "Building", "Installing", "Successfully"))]
    assert len(pip) >= 2, r.stdout
