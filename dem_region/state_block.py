"""The hosted models' state in one shared-memory block: what a sync copies instead of pickling.

Models that run in an engine's worker (law bonds, impactors) have copies in the orchestrator,
brought up to date before every read (a history sample, a frame, a checkpoint). Pickled over
the socket, a sync of 8,634 law bonds cost 0.84 ms (cfrp_beam_impact_3d_coarse on LAMMPS: 1.3 s
of transport in 1,518 samples, twice the engine's own time). Here the worker writes each
numeric array and scalar of the states (``model_step.model_states``) into a block the
orchestrator made to the layout the worker announced, and the orchestrator copies them out:
two memory copies and one short round trip. The layout (each entry's model, key, dtype, shape,
kind) changes only with the models (a grown zone: a new worker); a state that does not fit the
block's layout is announced again and a new block made. Anything not numeric travels pickled
beside it (``rest``).
"""
from __future__ import annotations

import numpy as np

ALIGN = 8  # bytes: every entry starts on a float64 boundary


def layout(states: list[dict]) -> tuple[list[tuple], list[dict]]:
    """(entries, rest) of model states: entries (model, key, dtype str, shape, kind) for the
    numeric arrays (kind "array") and scalars ("float", "int", "bool") in order; rest: per
    model, the values that are neither (pickled beside the block)."""
    entries, rest = [], []
    for i, d in enumerate(states):
        other = {}
        for key, v in d.items():
            if isinstance(v, np.ndarray) and v.dtype.kind in "fiub":
                entries.append((i, key, v.dtype.str, tuple(int(n) for n in v.shape), "array"))
            elif isinstance(v, (bool, np.bool_)):
                entries.append((i, key, "|b1", (), "bool"))
            elif isinstance(v, (int, np.integer)):
                entries.append((i, key, "<i8", (), "int"))
            elif isinstance(v, (float, np.floating)):
                entries.append((i, key, "<f8", (), "float"))
            else:
                other[key] = v
        rest.append(other)
    return entries, rest


def offsets(entries: list[tuple]) -> tuple[list[int], int]:
    """(each entry's byte offset, the block's size in bytes, at least 8)."""
    out, at = [], 0
    for _, _, dtype, shape, _ in entries:
        out.append(at)
        n = np.dtype(dtype).itemsize * int(np.prod(shape, dtype=np.int64))
        at += -(-n // ALIGN) * ALIGN
    return out, max(ALIGN, at)


def views(buf, entries: list[tuple]) -> list[np.ndarray]:
    """Each entry as an array on the block's buffer ``buf``."""
    at, _ = offsets(entries)
    return [np.ndarray(shape, dtype=np.dtype(dtype), buffer=buf, offset=o)
            for (_, _, dtype, shape, _), o in zip(entries, at)]


def write(on: list[np.ndarray], entries: list[tuple], states: list[dict]) -> None:
    """The states' values into the block's views ``on`` (entries from ``layout`` of the same
    states)."""
    for view, (i, key, _, _, _) in zip(on, entries):
        view[...] = states[i][key]


def write_if_fits(on: list[np.ndarray], entries: list[tuple], states: list[dict]) -> bool:
    """``write`` when ``states`` have exactly the block's layout (each entry's key, kind, dtype
    and shape, nothing beside them); else False and nothing written. One pass, no layout built:
    the worker's side of a sync at the end of each advance."""
    count = [0] * len(states)
    for view, (i, key, dtype, shape, kind) in zip(on, entries):
        v = states[i].get(key) if i < len(states) else None
        if kind == "array":
            if not (isinstance(v, np.ndarray) and v.shape == view.shape and v.dtype == view.dtype):
                return False
        elif kind == "bool":
            if not isinstance(v, (bool, np.bool_)):
                return False
        elif kind == "int":
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
                return False
        elif isinstance(v, (bool, np.bool_, int, np.integer)) or not isinstance(v, (float, np.floating)):
            return False
        count[i] += 1
    if any(c != len(d) for c, d in zip(count, states)):  # a key beside the layout (rest)
        return False
    write(on, entries, states)
    return True


def read(on: list[np.ndarray], entries: list[tuple], rest: list[dict], copy: bool = True) -> list[dict]:
    """The states written by ``write``: the arrays (copies; with ``copy=False`` views on the
    block, for a reader that copies what it keeps before the next sync rewrites it), scalars of
    their kind, and the rest."""
    states = [dict(r) for r in rest]
    kinds = {"float": float, "int": int, "bool": bool}
    for view, (i, key, _, _, kind) in zip(on, entries):
        if kind == "array":
            states[i][key] = view.copy() if copy else view
        else:
            states[i][key] = kinds[kind](view[()])
    return states
