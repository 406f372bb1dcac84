"""Write foxglove/slipreflex.json, the Foxglove layout of a run (live or recorded).

Panels after the paper's Fig. 10: the slip signal (raw, filtered, the threshold in force),
the spikes and each window's spike count, the MPI command with the grip it adds to each
finger, then the simulated rig's truth (``virtual-rig --live``), the IMU, the touch of a
tactile method and the faults.
Every series is a path into a topic of :data:`slipreflex.files.recording.TOPICS`; the layout is
built with the layout types foxglove-sdk ships (``foxglove.layouts``).

Usage::

    python -m scripts.dev.foxglove_layout            # rewrites foxglove/slipreflex.json
    python -m scripts.dev.foxglove_layout --check    # exit 1 if the file differs from what it builds
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "foxglove" / "slipreflex.json"

#: (panel title, y label, [(topic.field, label, colour, line or points)])
PANELS = [
    ("Slip sensor (Fig. 10a)", "V", [("/daq/samples.slip_volts", "raw", "#9e9e9e", "line"),
                                     ("/chain/state.filtered", "filtered", "#1f77b4", "line"),
                                     ("/chain/state.threshold", "threshold", "#d62728", "line")]),
    ("Spikes and window counts (Fig. 10b)", "spikes", [("/chain/windows.count", "spikes per window", "#ff7f0e", "line"),
                                                       ("/chain/state.event", "spike", "#2ca02c", "line")]),
    ("MPI command (Fig. 10c)", "i-Limb units", [("/hand/commands.target", "MPI command", "#000000", "line"),
                                                ("/hand/grip.thumb", "thumb grip", "#8c564b", "line"),
                                                ("/hand/grip.index", "index grip", "#9467bd", "line"),
                                                ("/hand/grip.middle", "middle grip", "#17becf", "line")]),
    ("Rig truth (virtual-rig --live)", "m", [("/rig/truth.displacement", "displacement", "#1f77b4", "line"),
                                             ("/rig/truth.slip", "slip", "#d62728", "line")]),
    ("IMU", "g", [("/daq/imu.ax", "ax", "#1f77b4", "line"), ("/daq/imu.ay", "ay", "#ff7f0e", "line"),
                  ("/daq/imu.az", "az", "#2ca02c", "line")]),
    ("Touch (a tactile method)", "N", [("/tactile/frames.total", "total", "#1f77b4", "line"),
                                       ("/tactile/frames.peak", "peak", "#d62728", "line")]),
]


#: Fields drawn as steps (they hold their value until the next message).
_STEPS = {"count", "event", "target", "thumb", "index", "middle"}


def series_paths() -> list[str]:
    """Every topic.field the layout plots (the test checks them against the schemas)."""
    return [path for _, _, series in PANELS for path, *_ in series] + ["/faults"]


def build() -> str:
    """The layout as JSON text."""
    import foxglove.layouts as fl

    plots = []
    for title, unit, series in PANELS:
        paths = [fl.PlotSeries(value=path, label=label, color=colour, show_line=kind == "line",
                               line_interpolation="step" if path.split(".")[-1] in _STEPS else None)
                 for path, label, colour, kind in series]
        plots.append(fl.PlotPanel(title=title, config=fl.PlotConfig(
            paths=paths, y_axis_label=unit, show_legend=True, legend_display="top", is_synced=True,
            time_window_mode="sliding", following_view_width=10.0)))
    fig10 = fl.SplitContainer(direction="column", items=[fl.SplitItem(content=p) for p in plots[:3]])
    side = fl.SplitContainer(direction="column", items=[
        fl.SplitItem(content=plots[3]), fl.SplitItem(content=plots[4]), fl.SplitItem(content=plots[5]),
        fl.SplitItem(content=fl.TablePanel(title="Faults", config=fl.TableConfig(topic_path="/faults")))])
    layout = fl.Layout(content=fl.SplitContainer(direction="row", items=[
        fl.SplitItem(proportion=2, content=fig10), fl.SplitItem(proportion=1, content=side)]))
    return json.dumps(json.loads(layout.to_json()), indent=1) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="compare with the file instead of writing it")
    args = ap.parse_args(argv)
    text = build()
    if args.check:
        same = OUT.exists() and OUT.read_text() == text
        print(f"{OUT.relative_to(ROOT)}: {'up to date' if same else 'differs from what this script builds'}")
        return 0 if same else 1
    OUT.write_text(text)
    print(f"wrote {OUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
