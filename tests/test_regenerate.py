"""scripts/regenerate.py rewrites every generated table the README and docs/ quote: each marker
pair there is written by one of its steps, and each step's script exists."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
try:
    import regenerate
finally:
    sys.path.pop(0)


def _markers() -> dict[str, str]:
    """``{marker name: file}`` of every ``<!-- NAME begins -->`` in README.md and docs/*.md."""
    out = {}
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = path.read_text()
        for name in re.findall(r"<!-- (.+?) begins -->", text):
            assert f"<!-- {name} ends -->" in text, f"{path.name}: '{name}' begins but never ends"
            out[name] = path.name
    return out


def test_every_generated_table_has_a_step_and_every_step_a_script():
    written = {m for _, markers, _ in regenerate.STEPS for m in markers}
    missing = {name: where for name, where in _markers().items() if name not in written}
    assert not missing, f"tables no step of scripts/regenerate.py writes: {missing}"
    assert _markers(), "no generated table found"
    for name, _, command in regenerate.STEPS:
        for part in command:
            if part.endswith(".py"):
                assert Path(part).exists(), f"step {name!r}: {part} does not exist"


def test_the_dry_run_lists_the_steps_in_order():
    res = subprocess.run([sys.executable, str(ROOT / "scripts" / "regenerate.py"), "--dry-run", "--jobs", "2"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert [line.split(":")[1].strip() for line in lines] == [name for name, _, _ in regenerate.STEPS]
    assert "--jobs 2" in lines[0] and "(writes: results table, claims table)" in lines[1]
