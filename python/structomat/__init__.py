"""structomat from Python: host-sim's runs and the Constantinesco converter's twin.

``structomat.run(source, **overrides)`` runs a built-in scenario (``structomat.scenarios()``)
or a run file exactly as ``host-sim run`` does (the same pipeline, in-process) and returns
a :class:`Result` whose ``columns`` are the CSV's columns as numpy arrays, bit for bit the
values of host-sim's CSV text read back. ``structomat.Twin`` steps the converter's twin
with per-step inputs, as the firmware does. Long runs release the GIL and answer Ctrl-C
(KeyboardInterrupt) within 0.1 s; errors are :class:`Error` with host-sim's message.
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Union

from . import _core
from ._core import Error, Twin, TwinError, __version__

__all__ = ["Error", "Result", "Twin", "TwinError", "design", "run", "scenarios", "sweep",
           "__version__"]


class Result:
    """What a run computed: its tables and its summary.

    ``columns``: the state table, column name -> float64 numpy array (``mode`` and
    ``coords`` of a converter run: a list of str); an empty cell (past a mode's DOF) is
    NaN. ``events`` and ``switches``: the converter's event and coordinate-switch logs,
    in the same form (empty dicts for a mechanism, whose dead-point switches are in
    ``summary["switches"]``). ``summary``: the summary's figures (``summary["text"]`` is
    the summary host-sim prints).
    """

    __slots__ = ("columns", "events", "switches", "summary")

    def __init__(self, columns: Dict[str, Any], events: Dict[str, Any],
                 switches: Dict[str, Any], summary: Dict[str, Any]) -> None:
        self.columns = columns
        self.events = events
        self.switches = switches
        self.summary = summary

    def __len__(self) -> int:
        """The state table's rows."""
        first = next(iter(self.columns.values()), [])
        return len(first)

    def __repr__(self) -> str:
        s = self.summary
        return (f"Result({s.get('scenario')!r}, {len(self)} rows, "
                f"{len(self.columns)} columns, end={s.get('end')!r})")


def run(source: Union[str, "os.PathLike[str]"], **overrides: Any) -> Result:
    """Runs ``source`` (a built-in scenario's name or a run file's path) as
    ``host-sim run`` does, with the keyword ``overrides`` of its options: ``h`` (or
    ``step``), ``t_end``, ``every``, ``f32``, ``f64``, ``motor``, ``load``, ``ccw``,
    ``spread_events``.

    An unknown keyword is a TypeError naming it; a value host-sim refuses, a run file
    that does not read or a run that cannot be set up raise :class:`Error` with
    host-sim's message. A step that fails after the run began raises :class:`Error`
    whose ``result`` holds the rows up to there (``host-sim run`` exits 1 then); a
    converter run ending at the mechanism's singularity (ccc-s1's expected end) returns
    normally with ``summary["end"] == "singularity"``. Ctrl-C raises KeyboardInterrupt.
    """
    columns, events, switches, summary, failure = _core.run(os.fspath(source), overrides)
    result = Result(columns, events, switches, summary)
    if failure is not None:
        err = Error(failure)
        err.result = result
        raise err
    return result


def scenarios() -> List[tuple]:
    """The built-in scenarios, ``(name, description)``, as ``host-sim list`` lists them."""
    return _core.scenarios()


def _sweep_batch(path: str, which: List[int]) -> list:
    """A Dask task: variants ``which`` of the sweep file ``path``, run in order (the GIL
    released), their outcomes."""
    return _core.sweep_run(path, list(which))


def sweep(path: Union[str, "os.PathLike[str]"], out_dir: Union[str, "os.PathLike[str]"],
          client: Any = None, batch: Optional[int] = None) -> Dict[str, Any]:
    """Runs the sweep file ``path``'s variants and writes ``sweep.csv`` and the heat-maps
    into ``out_dir``: the same files as ``host-sim sweep``, byte for byte, whatever runs
    them.

    ``client``: a ``dask.distributed.Client``; its workers run the variants as tasks of
    ``batch`` variants each (default: about four tasks a worker; a converter variant
    takes tens of milliseconds, so a task is well over Dask's ~10 ms per task), the GIL
    released in each; the rows are gathered in grid order. The file must be readable at
    the same path on the workers. ``None``: the variants run here, in this process, one
    batch after another. A variant whose run fails is a row saying how it ended; a
    worker lost mid-sweep has its tasks run again elsewhere (a task is pure: the same
    rows, once each). A bad sweep file or variant raises :class:`Error` before anything
    runs. Returns ``{"variants", "table", "heatmaps", "tasks"}``.
    """
    path = os.path.abspath(os.fspath(path))
    out_dir = os.fspath(out_dir)
    n = _core.sweep_plan(path)
    if batch is None:
        workers = 1
        if client is not None:
            workers = max(1, len(client.scheduler_info().get("workers", {})))
        batch = max(1, -(-n // (4 * workers)))
    if batch < 1:
        raise ValueError(f"batch: {batch} is not a positive number of variants")
    chunks = [list(range(k, min(n, k + batch))) for k in range(0, n, batch)]
    if client is None:
        parts = [_sweep_batch(path, c) for c in chunks]
    else:
        # pure=False: each chunk is its own task even where two chunks look alike.
        futures = [client.submit(_sweep_batch, path, c, pure=False) for c in chunks]
        parts = client.gather(futures)
    outcomes = [o for part in parts for o in part]
    table, heatmaps = _core.sweep_write(path, out_dir, outcomes)
    return {"variants": n, "table": table, "heatmaps": heatmaps, "tasks": len(chunks)}


def _design_task(path: str, x: List[float]) -> tuple:
    """A Dask task: design ``x`` of the design file ``path`` at every operating point
    (the GIL released), its score ``(violation, objective)``."""
    return _core.design_evaluate(path, list(x))


def design(path: Union[str, "os.PathLike[str]"], client: Any = None) -> Dict[str, Any]:
    """Runs the design file ``path``'s search (``host-sim design``'s optimizer), each
    generation's designs evaluated as Dask tasks, one design a task, on ``client``'s
    workers (``None``: here, in this process). The optimizer is replayed from its seed
    and the scores gathered in member order, so the best design is host-sim's, bit for
    bit, whatever runs the tasks. The file must be readable at the same path on the
    workers. A bad design file raises :class:`Error` before anything runs.

    Returns ``{"best": [free values], "violation", "objective", "feasible",
    "history": [[(violation, objective), ...] per generation], "tasks"}``; the
    objective is minimised (minus the mean power for ``mean_power``).
    """
    path = os.path.abspath(os.fspath(path))
    history: List[List[tuple]] = []
    tasks = 0
    while True:
        points = _core.design_ask(path, history)
        if points is None:
            break
        if client is None:
            scores = [_design_task(path, x) for x in points]
        else:
            futures = [client.submit(_design_task, path, x, pure=False) for x in points]
            scores = client.gather(futures)
        tasks += len(points)
        history.append([tuple(s) for s in scores])
    best = _core.design_best(path, history)
    if best is None:
        raise Error(f"{path}: no design was evaluated")
    x, violation, objective = best
    return {"best": list(x), "violation": violation, "objective": objective,
            "feasible": violation == 0.0 and objective == objective,
            "history": history, "tasks": tasks}
