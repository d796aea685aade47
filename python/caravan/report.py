"""Report plugins in Python: the protocol of the Rust crate ``caravan-report``
(``runtime/report/src/plugin.rs``), so that a script is a report plugin like a Rust binary.

The launcher runs each ``[[report]]`` entry's command twice: as ``PROGRAM --check`` before the
group starts (bad params stop the launch, exit 2, nothing started) and as ``PROGRAM RUN_DIR``
after the run. Both times the entry's ``params`` come as JSON in ``CARAVAN_PARAMS`` and the
directory of the launch file that named the plugin in ``CARAVAN_LAUNCH_DIR`` (relative paths in
params are relative to it). The plugin writes each section as ``RUN_DIR/sections/<name>.json``
(the section's value in ``report.json``) and ``sections/<name>.md`` (its part of ``report.md``,
starting with a ``## `` heading), plus any plots into ``RUN_DIR``. Exit codes: 0 done, 2 bad
params or input, 1 a failure while computing (the launcher lists it under
``failed_sections`` with the plugin's stderr).

A plugin in a few lines::

    from caravan import report

    @report.plugin("count-report", params={"topic": str, "field": "x"})
    def count(run, p):
        values = [getattr(m, p["field"]) for _, _, m in run.recording.messages(p["topic"])]
        return report.Section(
            "count",
            {"topic": p["topic"], "messages": len(values), "sum": sum(values)},
            f"## Count\\n\\n{len(values)} messages on `{p['topic']}`.\\n",
        )

    if __name__ == "__main__":
        count.main()

``params`` maps each key to its default, or to a type (``str``, ``float``, ``list``…) for a
required key; an unknown key, a missing one or a value of another type exits 2 naming the key.
``setup=`` (``setup(params, inputs)``) checks and loads more (files the params name) in both
runs; what it returns is what the section function gets.
"""

from __future__ import annotations

import json
import math
import os
import sys
import traceback
from pathlib import Path
from typing import Any, Callable, Iterable, Optional, Union

from .identity import CaravanError

__all__ = [
    "BadParams",
    "Inputs",
    "RESERVED",
    "Run",
    "SECTIONS_DIR",
    "Section",
    "check_name",
    "line_plot",
    "main",
    "parse_params",
    "plugin",
    "run_plugin",
]

# Where plugins leave their sections, inside the run directory (caravan_report::SECTIONS_DIR).
SECTIONS_DIR = "sections"
# Names the generic report uses; a plugin's section may not take them (caravan_report::RESERVED).
RESERVED = ("version", "group", "run", "nodes", "topics", "links")
# The launcher's files in a run directory (caravan_report::{FACTS_FILE, RECORDING_FILE}).
FACTS_FILE = "run.json"
RECORDING_FILE = "record.mcap"
ENV_PARAMS = "CARAVAN_PARAMS"
ENV_LAUNCH_DIR = "CARAVAN_LAUNCH_DIR"


class BadParams(CaravanError):
    """Bad params or input named by them: exit 2, before the group starts."""


class Section:
    """One section of a run's report."""

    def __init__(self, name: str, json: Any, markdown: str):
        #: The key in ``report.json``: lower case letters, digits and ``_``.
        self.name = name
        #: The section's value in ``report.json`` (NaN and infinities are written as null).
        self.json = json
        #: Its part of ``report.md``, starting with a ``## `` heading.
        self.markdown = markdown

    def write(self, run_dir: Union[str, os.PathLike]) -> None:
        """Writes ``sections/<name>.json`` and ``sections/<name>.md`` into ``run_dir``."""
        check_name(self.name)
        if not self.markdown.startswith("## "):
            raise ValueError(
                f"section '{self.name}': its Markdown must start with a '## ' heading"
            )
        directory = Path(run_dir) / SECTIONS_DIR
        directory.mkdir(parents=True, exist_ok=True)
        # As serde_json writes it (to_string_pretty and a newline): the launcher merges the
        # text verbatim, and reads NaN as an error, so it is null, as Rust writes NaN.
        text = json.dumps(_finite(self.json), indent=2, ensure_ascii=False, allow_nan=False)
        (directory / f"{self.name}.json").write_text(text + "\n", encoding="utf-8")
        (directory / f"{self.name}.md").write_text(self.markdown, encoding="utf-8")

    def __repr__(self) -> str:
        return f"Section({self.name!r})"


def check_name(name: str) -> None:
    """Refuses a name the launcher would not merge (caravan_report's ``check_name``)."""
    valid = bool(name) and all(c.isascii() and (c.islower() or c.isdigit() or c == "_")
                               for c in name)
    if not valid:
        raise ValueError(f"section name '{name}' must be lower case letters, digits and '_'")
    if name in RESERVED:
        raise ValueError(f"section name '{name}' is the generic report's own")


def _finite(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


class Inputs:
    """Where a plugin's relative paths start: the directory of the launch file that named it."""

    def __init__(self, launch_dir: Union[str, os.PathLike]):
        self.launch_dir = Path(launch_dir)

    def path(self, path: Union[str, os.PathLike]) -> Path:
        """``path`` relative to the launch file (an absolute path stays as it is)."""
        return self.launch_dir / path


class Run:
    """One finished run: its directory, the launcher's facts (``run.json``) and its recording
    (opened on first use)."""

    def __init__(self, run_dir: Union[str, os.PathLike]):
        self.dir = Path(run_dir)
        path = self.dir / FACTS_FILE
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as e:
            raise CaravanError(f"cannot read {path}: {e.strerror or e}") from None
        try:
            #: ``run.json``: outcome, processes, node statuses, the report entries…
            self.facts = json.loads(text)
        except ValueError as e:
            raise CaravanError(f"{path} is not a Caravan run record: {e}") from None
        self._recording = None

    @property
    def recording(self):
        """``record.mcap`` as a ``caravan.recording.Recording``."""
        if self._recording is None:
            from . import recording

            self._recording = recording.open(self.dir / RECORDING_FILE)
        return self._recording

    def messages(self, topics=None, start_ns=None, end_ns=None):
        """The recording's messages (``Recording.messages``)."""
        return self.recording.messages(topics, start_ns, end_ns)

    def path(self, name: str) -> Path:
        """Where a plot or other file called ``name`` goes: into the run directory."""
        return self.dir / name


# --- params ----------------------------------------------------------------------------------

_TYPE_NAMES = {str: "a string", float: "a number", int: "an integer", bool: "true or false",
               list: "a list", dict: "a table"}


def _fits(value, kind: type) -> bool:
    if kind is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind is int:
        return isinstance(value, int) and not isinstance(value, bool)
    return isinstance(value, kind)


def parse_params(raw: Any, spec: Optional[dict]) -> dict:
    """``raw`` checked against ``spec`` (key to default, or to a type for a required key),
    with the defaults filled in; ``spec=None`` takes any table as it is."""
    if not isinstance(raw, dict):
        raise BadParams("params must be a table")
    if spec is None:
        return dict(raw)
    unknown = [k for k in raw if k not in spec]
    if unknown:
        keys = ", ".join(f"'{k}'" for k in unknown)
        raise BadParams(f"unknown key {keys}; this report does not take it")
    out = {}
    for key, rule in spec.items():
        kind = rule if isinstance(rule, type) else type(rule)
        if key not in raw:
            if isinstance(rule, type):
                raise BadParams(f"missing key '{key}'")
            out[key] = rule
            continue
        value = raw[key]
        if rule is not None and not _fits(value, kind):
            expected = _TYPE_NAMES.get(kind, kind.__name__)
            raise BadParams(f"key '{key}': expected {expected}, got {json.dumps(value)}")
        out[key] = float(value) if kind is float else value
    return out


# --- the process -----------------------------------------------------------------------------

SectionsFn = Callable[[Run, Any], Union[Section, Iterable[Section], None]]


def run_plugin(
    program: str,
    sections: SectionsFn,
    params: Optional[dict] = None,
    setup: Optional[Callable[[dict, Inputs], Any]] = None,
    argv: Optional[list] = None,
    env: Optional[dict] = None,
) -> int:
    """Runs a plugin as the launcher expects (see the module documentation); returns the exit
    code. ``sections(run, ready)`` gets what ``setup`` returned (else the parsed params)."""
    args = sys.argv[1:] if argv is None else argv
    env = os.environ if env is None else env

    def fail(code: int, message: str) -> int:
        print(f"{program}: {message}", file=sys.stderr)
        return code

    if len(args) == 1 and args[0] == "--check":
        run_dir = None
    elif len(args) == 1 and not args[0].startswith("-"):
        run_dir = args[0]
    else:
        return fail(2, f"usage: {program} --check | {program} RUN_DIR (params in {ENV_PARAMS})")
    try:
        raw = json.loads(env.get(ENV_PARAMS) or "{}")
    except ValueError as e:
        return fail(2, f"{ENV_PARAMS} is not JSON: {e}")
    inputs = Inputs(env.get(ENV_LAUNCH_DIR) or ".")
    try:
        parsed = parse_params(raw, params)
        ready = parsed if setup is None else setup(parsed, inputs)
    except (BadParams, ValueError, OSError) as e:
        return fail(2, f"params of report '{program}': {e}")
    if run_dir is None:
        return 0
    try:
        run = Run(run_dir)
        written = sections(run, ready)
        if isinstance(written, Section):
            written = [written]
        for section in written or []:
            section.write(run.dir)
    except CaravanError as e:
        return fail(1, str(e))
    except Exception as e:  # noqa: BLE001 - any failure is the plugin's, reported in one line
        where = traceback.extract_tb(e.__traceback__)[-1]
        return fail(1, f"{type(e).__name__}: {e} ({Path(where.filename).name}:{where.lineno})")
    return 0


def main(program: str, sections: SectionsFn, params=None, setup=None) -> None:
    """Runs the plugin and exits with its code."""
    sys.exit(run_plugin(program, sections, params, setup))


class _Plugin:
    def __init__(self, program, sections, params, setup):
        self.program, self.sections, self.params, self.setup = program, sections, params, setup

    def __call__(self, run: Run, ready: Any):
        return self.sections(run, ready)

    def run(self, argv=None, env=None) -> int:
        return run_plugin(self.program, self.sections, self.params, self.setup, argv, env)

    def main(self) -> None:
        sys.exit(self.run())


def plugin(program: str, params: Optional[dict] = None, setup=None):
    """Decorates ``sections(run, ready)`` into a plugin; call ``.main()`` on it."""
    return lambda sections: _Plugin(program, sections, params, setup)


# --- plots -----------------------------------------------------------------------------------


def line_plot(path, series: dict, title: str = "", x_label: str = "", y_label: str = "",
              equal_axes: bool = False) -> None:
    """A small SVG line plot of ``series`` (label to a list of ``(x, y)``) at ``path``, with
    the axes' ranges written at their ends; with ``equal_axes`` one unit is as long on both
    axes (trajectories), the data centred in the frame."""
    points = [(x, y) for s in series.values() for x, y in s
              if math.isfinite(x) and math.isfinite(y)]
    width, height, margin = 640, 480, 56
    x0, x1 = (min(p[0] for p in points), max(p[0] for p in points)) if points else (0, 1)
    y0, y1 = (min(p[1] for p in points), max(p[1] for p in points)) if points else (0, 1)
    inner_w, inner_h = width - 2 * margin, height - 2 * margin
    if equal_axes:
        # One scale for both; the shorter side's range widened about its centre to fill.
        scale = min(inner_w / ((x1 - x0) or 1.0), inner_h / ((y1 - y0) or 1.0))
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        x0, x1 = cx - inner_w / scale / 2, cx + inner_w / scale / 2
        y0, y1 = cy - inner_h / scale / 2, cy + inner_h / scale / 2
    sx, sy = inner_w / ((x1 - x0) or 1.0), inner_h / ((y1 - y0) or 1.0)

    def at(x, y):
        return f"{margin + (x - x0) * sx:.2f},{height - margin - (y - y0) * sy:.2f}"

    colours = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2"]
    bottom, right = height - margin, width - margin
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'font-family="sans-serif" font-size="12">',
        f'<rect width="{width}" height="{height}" fill="white"/>',
        f'<rect x="{margin}" y="{margin}" width="{inner_w}" height="{inner_h}" fill="none" '
        f'stroke="#888"/>',
        f'<text x="{width / 2}" y="24" text-anchor="middle" font-size="14">{_xml(title)}</text>',
        f'<text x="{width / 2}" y="{height - 14}" text-anchor="middle">{_xml(x_label)}</text>',
        f'<text x="{margin}" y="{bottom + 16}" text-anchor="start">{x0:.4g}</text>',
        f'<text x="{right}" y="{bottom + 16}" text-anchor="end">{x1:.4g}</text>',
        f'<text x="16" y="{height / 2}" transform="rotate(-90 16 {height / 2})" '
        f'text-anchor="middle">{_xml(y_label)}</text>',
        f'<text x="{margin - 4}" y="{bottom}" text-anchor="end">{y0:.4g}</text>',
        f'<text x="{margin - 4}" y="{margin + 10}" text-anchor="end">{y1:.4g}</text>',
    ]
    for i, (label, s) in enumerate(series.items()):
        colour = colours[i % len(colours)]
        drawn = " ".join(at(x, y) for x, y in s if math.isfinite(x) and math.isfinite(y))
        out.append(f'<polyline fill="none" stroke="{colour}" stroke-width="1.5" '
                   f'points="{drawn}"/>')
        out.append(f'<text x="{right - 6}" y="{margin + 16 + 16 * i}" text-anchor="end" '
                   f'fill="{colour}">{_xml(label)}</text>')
    out.append("</svg>\n")
    Path(path).write_text("\n".join(out), encoding="utf-8")


def _xml(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
