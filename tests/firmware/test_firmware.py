"""The AVR firmware: build, shared test vectors in C, and runs under simavr.

Needs avr-gcc, avr-libc, simavr, libsimavr-dev, libelf-dev and pkg-config (installed by
scripts/bootstrap.sh); without them these tests skip, naming the missing tool, except under
``SLIPREFLEX_REQUIRE_TOOLS=1`` (set by ``scripts/bootstrap.sh test``, so CI never skips them).
"""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from slipreflex.core import hardware
from slipreflex.rig.devices import wire

ROOT = Path(__file__).resolve().parents[2]
FIRMWARE = ROOT / "firmware"
VECTORS = ROOT / "tests" / "data" / "wire" / "vectors.txt"
SECONDS = 30


def _load_checker():
    path = FIRMWARE / "test" / "check_capture.py"
    spec = importlib.util.spec_from_file_location("slipreflex_fw_check_capture", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


checker = _load_checker()


@pytest.fixture(scope="module")
def build(tmp_path_factory, tools):
    """Build everything into a private directory; return (dir, make output)."""
    tools("make", "cc", "avr-gcc", "avr-libc", "simavr")
    out = tmp_path_factory.mktemp("fw") / "build"
    proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={out}"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out, proc.stdout + proc.stderr


def _harness(build_dir: Path, elf: str, outdir: Path, seconds: float, *args: str) -> str:
    outdir.mkdir(parents=True, exist_ok=True)
    proc = subprocess.run([str(build_dir / "harness"), str(build_dir / elf), str(outdir),
                           str(seconds), *args], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


@pytest.fixture(scope="module")
def good_capture(build, tmp_path_factory):
    out = tmp_path_factory.mktemp("good")
    _harness(build[0], "daq.elf", out, SECONDS)
    return out


@pytest.mark.slow
def test_build_is_strict_and_reports_size(build):
    build_dir, log = build
    assert "-Wall -Wextra -Werror" in log
    assert f"-DF_CPU={hardware.F_CPU}UL" in log
    m = re.search(r"firmware size: flash (\d+) of 32768 bytes .*RAM (\d+) of 2048 bytes", log)
    assert m, log
    flash, ram = int(m[1]), int(m[2])
    assert 500 < flash < 8192 and 16 < ram < 512
    for elf, total in (("daq-reflex", 32768), ("hand2560", 262144)):
        m = re.search(rf"{elf} size: flash (\d+) of {total} bytes .*RAM (\d+) of", log)
        assert m, log
        assert flash < int(m[1]) < 8192 and ram < int(m[2]) < 512
        assert (build_dir / f"{elf}.hex").read_text().startswith(":")
    assert "-mmcu=atmega2560" in log and "-DHAND_UART1" in log
    assert (build_dir / "daq.hex").read_text().startswith(":")


def test_c_header_matches_python():
    text = (FIRMWARE / "src" / "wire.h").read_text()
    defs = {k: int(v.rstrip("uUlL"), 0) for k, v in
            re.findall(r"#define (WIRE_\w+) (0x[0-9A-Fa-f]+u?|\d+[uUlL]*)", text)}
    assert defs == {
        "WIRE_SYNC0": wire.SYNC[0], "WIRE_SYNC1": wire.SYNC[1], "WIRE_VERSION": wire.VERSION,
        "WIRE_FRAME_LEN": wire.FRAME_LEN, "WIRE_BAUD": wire.BAUD, "WIRE_ADC_MAX": wire.ADC_MAX,
        "WIRE_FLAG_ACCEL_FRESH": wire.FLAG_ACCEL_FRESH, "WIRE_FLAG_IMU_ERROR":
        wire.FLAG_IMU_ERROR, "WIRE_FLAG_OVERRUN": wire.FLAG_OVERRUN,
        "WIRE_VERSION_REFLEX": wire.VERSION_REFLEX, "WIRE_FRAME_LEN_REFLEX": wire.FRAME_LEN_REFLEX,
        "WIRE_REFLEX_SPIKE": wire.REFLEX_SPIKE, "WIRE_REFLEX_WINDOW": wire.REFLEX_WINDOW,
        "WIRE_REFLEX_FAULT": wire.REFLEX_FAULT, "WIRE_REFLEX_HAND": wire.REFLEX_HAND,
    }


@pytest.mark.slow
def test_c_encoder_passes_shared_vectors(build):
    proc = subprocess.run([str(build[0] / "test_vectors"), str(VECTORS)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout
    assert re.search(r"13 good frames, 17 bad frames checked, \d+ streams skipped, 0 failures",
                     proc.stdout), proc.stdout


@pytest.mark.slow
@pytest.mark.parametrize("mutate", ["field", "reason", "hex"])
def test_c_vector_test_catches_a_wrong_vector(build, tmp_path, mutate):
    lines = VECTORS.read_text().splitlines()
    if mutate == "field":      # a good frame whose decoded adc is off by one
        i = next(i for i, ln in enumerate(lines) if ln.startswith("F basic "))
        parts = lines[i].split(" ")
        parts[5] = str(int(parts[5]) + 1)
    elif mutate == "reason":   # a bad-CRC frame declared truncated
        i = next(i for i, ln in enumerate(lines) if ln.startswith("B crc_low_bit "))
        parts = lines[i].split(" ")
        parts[3] = "truncated"
    else:                      # a good frame with one bit flipped in its bytes
        i = next(i for i, ln in enumerate(lines) if ln.startswith("F zero "))
        parts = lines[i].split(" ")
        parts[2] = parts[2][:10] + ("1" if parts[2][10] != "1" else "0") + parts[2][11:]
    lines[i] = " ".join(parts)
    bad = tmp_path / "vectors.txt"
    bad.write_text("\n".join(lines) + "\n")
    proc = subprocess.run([str(build[0] / "test_vectors"), str(bad)], capture_output=True,
                          text=True)
    assert proc.returncode == 1 and "FAIL" in proc.stdout, proc.stdout


@pytest.mark.slow
def test_simavr_run_is_clean_and_on_time(good_capture):
    rep = checker.check(good_capture)
    assert rep.ok, rep.summary()
    assert rep.seconds == pytest.approx(SECONDS, abs=0.01)
    assert rep.frames >= SECONDS / hardware.DAQ_PERIOD_S - 2
    assert rep.stats.crc_errors == 0 and rep.stats.seq_gaps == 0
    assert abs(rep.period_uart_cycles / checker.PERIOD_CYCLES - 1) < 1e-4
    assert abs(rep.period_adc_cycles / checker.PERIOD_CYCLES - 1) < 1e-4
    assert rep.fresh_frames >= rep.frames - checker.IMU_STARTUP_FRAMES
    assert rep.flow_pulses == pytest.approx(97 * SECONDS, abs=3)
    assert 0 < rep.busy_share <= 0.05                # the DAQ-alone budget, 5 % (simulated cycles)


@pytest.mark.slow
def test_decoded_samples_carry_injected_values(good_capture):
    """End to end through DaqSample: volts, g and time, against the harness's log."""
    parser = wire.FrameParser()
    samples = [f.to_sample() for f in parser.feed((good_capture / "uart.bin").read_bytes())]
    events = (good_capture / "events.txt").read_text().splitlines()
    counts = [int(ln.split()[2]) for ln in events if ln.startswith("A ")][: len(samples)]
    np.testing.assert_allclose([s.slip_volts for s in samples],
                               np.array(counts) * hardware.ADC_LSB)
    assert samples[-1].t == pytest.approx((len(samples) - 1) * hardware.DAQ_PERIOD_S)
    first = next(ln for ln in events if ln.startswith("I ")).split()[2:]
    fresh = next(s for s in samples if s.accel_g is not None)
    assert fresh.accel_g == tuple(int(v) / wire.ACCEL_LSB_PER_G for v in first)


@pytest.mark.slow
def test_negative_control_wrong_build_is_rejected(build, tmp_path):
    """Firmware built with an off-by-one timer compare value (3.0005 ms, +167 ppm)."""
    _harness(build[0], "daq-wrong-period.elf", tmp_path, SECONDS)
    rep = checker.check(tmp_path)
    assert not rep.ok
    assert all("sample period" in e for e in rep.errors), rep.errors
    assert len(rep.errors) == 2


def _copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst


@pytest.mark.slow
@pytest.mark.parametrize("damage, words", [
    ("flip", "crc errors"),
    ("drop", "seq gaps"),
    ("value", "wrong ADC count"),
    ("accel", "accelerometer readings do not come back"),
    ("pulse", "impossible flow count"),
    ("stretch", "sample period"),
])
def test_negative_control_corrupted_capture_is_rejected(good_capture, tmp_path, damage, words):
    out = _copy(good_capture, tmp_path / "cap")
    data = bytearray((out / "uart.bin").read_bytes())
    cycles = np.fromfile(out / "uart_cycles.bin", dtype="<u8")
    k = 5000 * wire.FRAME_LEN
    if damage == "flip":         # one bit error on the line
        data[k + 7] ^= 0x04
    elif damage == "drop":       # one whole frame lost
        del data[k:k + wire.FRAME_LEN]
        cycles = np.delete(cycles, np.s_[k:k + wire.FRAME_LEN])
    elif damage in ("value", "accel", "pulse"):  # the log disagrees with what came back
        ev = (out / "events.txt").read_text().splitlines()
        kind = {"value": "A ", "accel": "I ", "pulse": "P "}[damage]
        i = [j for j, ln in enumerate(ev) if ln.startswith(kind)][1234]
        parts = ev[i].split(" ")
        if damage == "pulse":    # one pulse the firmware counted never happened
            del ev[i]
        else:
            parts[2] = str((int(parts[2]) + 1) % 1024)
            ev[i] = " ".join(parts)
        (out / "events.txt").write_text("\n".join(ev) + "\n")
    else:                        # the UART clock 0.02 % slow from the middle on
        cycles = cycles.copy()
        cycles[k:] = cycles[k] + ((cycles[k:] - cycles[k]) * 1.0004).astype(np.uint64)
    (out / "uart.bin").write_bytes(bytes(data))
    cycles.astype("<u8").tofile(out / "uart_cycles.bin")
    rep = checker.check(out)
    assert not rep.ok
    assert any(words in e for e in rep.errors), rep.errors


@pytest.mark.slow
def test_without_imu_frames_keep_coming_flagged(build, tmp_path):
    _harness(build[0], "daq.elf", tmp_path, 10, "--no-imu")
    rep = checker.check(tmp_path, imu=False)
    assert rep.ok, rep.summary()
    assert rep.fresh_frames == 0 and rep.frames >= 3330
    # The same capture fails the checks for a board with its IMU present.
    assert any("IMU_ERROR" in e for e in checker.check(tmp_path, imu=True).errors)


@pytest.mark.slow
def test_imu_plugged_in_later_is_configured_and_read(build, tmp_path):
    """No IMU for the first second, then one appears (asleep, as at power-on): the
    firmware keeps streaming, flags IMU_ERROR meanwhile, then configures and reads it."""
    _harness(build[0], "daq.elf", tmp_path, 3, "--imu-from", "1.0")
    parser = wire.FrameParser()
    frames = parser.feed((tmp_path / "uart.bin").read_bytes())
    assert len(frames) >= 998 and parser.stats.seq_gaps == 0 and parser.stats.crc_errors == 0
    plug = round(1.0 / hardware.DAQ_PERIOD_S)
    assert all(f.imu_error and not f.accel_fresh for f in frames[:plug])
    assert all(f.accel_fresh and not f.imu_error for f in frames[plug + 5:])
    writes = [ln.split() for ln in (tmp_path / "events.txt").read_text().splitlines()
              if ln.startswith("W ")]
    assert [(int(r), int(v)) for _, _, r, v in writes] == list(checker.IMU_CONFIG.items())
    assert all(int(c) > hardware.F_CPU for _, c, _, _ in writes)


@pytest.mark.slow          # five AVR builds; the fast tier keeps the firmware's other checks
def test_reflex_settings_are_dependencies_of_the_firmware(tmp_path):
    """`make REFLEX_P0=125` after a normal build rebuilds the reflex firmware; back to 0 rebuilds again."""
    out = tmp_path / "build"
    targets = [str(out / "daq-reflex.hex"), str(out / "hand2560.hex")]

    def make(*settings: str) -> dict[str, bytes]:
        proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={out}", *settings, *targets],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        return {t: Path(t).read_bytes() for t in targets}

    first = make()
    changed = make("REFLEX_P0=125")
    assert all(changed[t] != first[t] for t in targets)
    assert make("REFLEX_P0=125") == changed          # same settings: nothing rebuilt, same bits
    assert make("REFLEX_DATH=0", "REFLEX_P0=125") != changed
    assert make() == first                           # back to the defaults: the defaults' firmware
