"""Typed, range-checked case parameters addressed by flat dotted keys.

A scene declares its parameters once, as ``{"material.E": Param(...)}``; the same dotted
keys are read from the case file's TOML tables, accepted by ``--set key=value`` and echoed
under ``"parameters"`` in summary.json. Every value is SI.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from typing import Any, Callable


class CaseError(ValueError):
    """Bad input: one line naming the key, the value and what is allowed (exit code 2)."""


@dataclass(frozen=True)
class Param:
    """One case parameter.

    kind: "float" | "int" | "str" | "bool" | "table" (rows of [time, value], time strictly
    increasing: a load history, as LS-DYNA's *DEFINE_CURVE); low/high: inclusive bounds unless
    ``open_low``/``open_high``; choices: the allowed strings; unit: SI unit for messages.
    """

    default: Any
    doc: str = ""
    kind: str = "float"
    unit: str = ""
    low: float | None = None
    high: float | None = None
    open_low: bool = False
    open_high: bool = False
    choices: tuple[str, ...] | None = None
    plausible: tuple[float, float] | None = None  # SI range outside which a value is a unit slip
    check: Callable[[Any], Any] | None = None  # a parser that raises ValueError("what is allowed")

    def allowed(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind == "bool":
            return "true or false"
        num = (lambda v: str(int(v))) if self.kind == "int" else (lambda v: f"{v:g}")  # a seed's 2147483647 in full
        parts = []
        if self.low is not None:
            parts.append(f"{'>' if self.open_low else '>='} {num(self.low)}")
        if self.high is not None:
            parts.append(f"{'<' if self.open_high else '<='} {num(self.high)}")
        if self.kind == "table":
            return "a list of at least two [time, value] rows, times increasing"
        what = {"float": "a number", "int": "an integer", "str": "a string"}[self.kind]
        text = what + (" " + " and ".join(parts) if parts else "") + (f" [{self.unit}]" if self.unit else "")
        if self.plausible and ((self.low is None or self.low < self.plausible[0])
                               or (self.high is None or self.high > self.plausible[1])):  # (coerce refuses a unit slip)
            text += f" (in SI: {self.plausible[0]:g} to {self.plausible[1]:g})"
        return text

    def coerce(self, key: str, value: Any, typed: bool = False) -> Any:
        """Return the value in this parameter's type, or raise CaseError.

        typed: the value comes from a case file, whose TOML says its type: text ("5", "true")
        for a number or a switch, and a fraction (5.0) for an integer, are refused there (a
        quoted number is most often a slip); text from --set is parsed.
        """
        bad = CaseError(f"{key} = {value!r}: expected {self.allowed()}")
        if typed and isinstance(value, str) and self.kind != "str":
            raise CaseError(f"{key} = {value!r}: expected {self.allowed()} (unquoted in a case file)")
        if self.kind == "table":
            return _table(value, bad)
        if isinstance(value, str) and self.kind != "str":
            value = _parse_scalar(value)
        if typed and self.kind == "int" and isinstance(value, float):
            raise CaseError(f"{key} = {value!r}: expected {self.allowed()} (no decimal point in a case file)")
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise bad
            return value
        if self.kind == "str":
            if not isinstance(value, str):
                raise bad
            if self.check is not None:  # what is malformed first, then whether it is one of the choices
                try:
                    self.check(value)
                except ValueError as exc:
                    raise CaseError(f"{key} = {value!r}: {exc}") from None
            if self.choices and value not in self.choices:
                raise bad
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise bad
        if self.kind == "int":
            if isinstance(value, float) and not value.is_integer():
                raise bad
            value = int(value)
        else:
            try:
                value = float(value)
            except OverflowError:  # an integer of hundreds of digits
                raise bad from None
            if not math.isfinite(value):
                raise bad
        if self.low is not None and (value < self.low or (self.open_low and value == self.low)):
            raise bad
        if self.high is not None and (value > self.high or (self.open_high and value == self.high)):
            raise bad
        if self.plausible and not self.plausible[0] <= value <= self.plausible[1]:
            raise CaseError(f"{key} = {value!r}: implausible in SI units [{self.unit}]; allowed "
                            f"{self.plausible[0]:g} to {self.plausible[1]:g} (case files are SI: Pa, kg/m^3, m, s)")
        return value


def _table(value: Any, bad: Exception) -> tuple[tuple[float, float], ...]:
    """Rows [time, value] (a TOML array of arrays, or its text from --set), times increasing."""
    if isinstance(value, str):
        try:
            value = tomllib.loads(f"v = {value}")["v"]
        except tomllib.TOMLDecodeError:
            raise bad from None
    num = lambda v: not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)
    if (not isinstance(value, (list, tuple)) or len(value) < 2
            or any(not isinstance(r, (list, tuple)) or len(r) != 2 or not all(map(num, r)) for r in value)
            or any(b[0] <= a[0] for a, b in zip(value, value[1:]))):
        raise bad
    return tuple((float(t), float(f)) for t, f in value)


def _parse_scalar(text: str) -> Any:
    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    try:
        return int(low)
    except ValueError:
        pass
    try:
        return float(low)
    except ValueError:
        return text


def positive(default: float, doc: str, unit: str) -> Param:
    """A strictly positive real number."""
    return Param(default, doc, "float", unit, low=0.0, open_low=True)


MODULUS_SI = (1e6, 1e13)  # Pa: rubber to diamond; a value outside it was not given in Pa
DENSITY_SI = (100.0, 3e4)  # kg/m^3: the solids of this project (a g/cm^3 slip lands below)


def modulus(default: float, doc: str) -> Param:
    return Param(default, doc, "float", "Pa", low=0.0, open_low=True, plausible=MODULUS_SI)


def density(default: float, doc: str = "density") -> Param:
    return Param(default, doc, "float", "kg/m^3", low=0.0, open_low=True, plausible=DENSITY_SI)


PARTICLE_SI = (1e-6, 1.0)  # m: a micron to a metre; outside it the value was not given in metres


def particle_radius(default: float, doc: str) -> Param:
    """A DEM particle radius (m), with the plausible range of this project's particles."""
    return Param(default, doc, "float", "m", low=0.0, open_low=True, plausible=PARTICLE_SI)


def particle_size(default: float, doc: str) -> Param:
    """A DEM particle size d (m): a diameter, the spacing of a lattice."""
    return Param(default, doc, "float", "m", low=0.0, open_low=True, plausible=PARTICLE_SI)


def isotropic_material(E: float, rho: float, poisson: float | None = None) -> dict[str, Param]:
    """material.E, material.rho (and material.poisson) with the given defaults."""
    out = {"material.E": modulus(E, "Young's modulus"), "material.rho": density(rho)}
    if poisson is not None:
        out["material.poisson"] = Param(poisson, "Poisson ratio", low=-0.99, high=0.49)
    return out


def flatten(table: dict, prefix: str = "") -> dict[str, Any]:
    """Nested TOML tables -> {"a.b.c": value}."""
    flat = {}
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            flat.update(flatten(v, key + "."))
        else:
            flat[key] = v
    return flat


# keys that were renamed (one concept, one key): the old key is refused with its new name, the
# first of these the case has (with what changed, if more than the name)
RENAMED: dict[str, tuple[tuple[str, str], ...]] = {
    "interface.tie": (("coupling.tie", ""),), "interface.tie_penalty": (("coupling.tie_penalty", ""),),
    "particle.radius": (("zone.particle_size", " = twice the old radius"), ("sphere.radius", "")),
    "dem.particle_size": (("zone.particle_size", ""),), "dem.half_width": (("zone.half_width", ""),),
    "dem.window_ahead": (("zone.window_ahead", ""),), "dem.window_behind": (("zone.window_behind", ""),),
    "dem.ply_failure": (("zone.ply_failure", ""),),
}


def resolve(schema: dict[str, Param], given: dict[str, Any], where: str,
            renamed: Callable[[str], str | None] | None = None, typed: bool = False) -> dict[str, Any]:
    """Defaults overlaid with ``given`` (flat dotted keys), every value checked.

    where: what supplied ``given`` ("case file x.toml", "--set"), for the error line;
    typed: ``given`` comes from TOML, whose values carry their type (Param.coerce);
    renamed: old key -> its new name (None if it never existed), for the error line.
    """
    unknown = sorted(set(given) - set(schema))
    if unknown:
        key = unknown[0]
        new = next((k + note for k, note in RENAMED.get(key, ()) if k in schema), None)
        new = new or (renamed(key) if renamed else None)
        if new and new.split()[0] in schema:  # (a renaming to a key this case lacks is no answer)
            raise CaseError(f"{key}: renamed, now {new} (in {where})")
        near = [k for k in schema if k.split(".")[-1] == key.split(".")[-1] or k.startswith(key.split(".")[0] + ".")]
        hint = f"; known keys here: {', '.join(sorted(near)[:8])}" if near else ""
        raise CaseError(f"{key}: unknown key in {where}{hint}")
    out = {k: p.default for k, p in schema.items()}
    for k, v in given.items():
        out[k] = schema[k].coerce(k, v, typed)
    return out


def parse_set(items: list[str]) -> dict[str, Any]:
    """``["a.b=1", ...]`` -> {"a.b": "1"} (types are coerced against the schema later)."""
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise CaseError(f"--set {item!r}: expected key=value with a dotted key and a value, e.g. material.E=7e10")
        if key.strip() in out and out[key.strip()] != value.strip():
            raise CaseError(f"--set {key.strip()}: given twice ({out[key.strip()]!r}, {value.strip()!r}); "
                            "allowed: one value per key")
        out[key.strip()] = value.strip()
    return out
