"""A study's standard plots: every probe's history (with its check's reference), and the
damage pictures of the particle zone."""
from __future__ import annotations

import numpy as np

from .closed_forms import CLOSED_FORMS
from .schema import section

_UNIT = {"point_displacement": ("mm", 1e3), "contact_force": ("kN", 1e-3), "delamination": ("mm", 1e3),
         "ply_cracks": ("bonds", 1.0), "zone_edge_damage": ("", 1.0), "applied_load": ("kN", 1e-3),
         "fibre_stress": ("MPa", 1e-6), "flexural_cracks": ("mm", 1e3), "debonding": ("mm", 1e3),
         "impactor_motion": ("m/s", 1.0), "interface_damage": ("mm^2", 1e6)}
# the series a panel draws, when not the probe's own name
_SERIES = {"flexural_cracks": ("{n}_height",), "debonding": ("{n}_length", "{n}_damaged_length"),
           "impactor_motion": ("{n}_velocity",), "interface_damage": ("debonded_area", "damaged_area")}


def _series(name: str, kind: str, h: dict) -> list[str]:
    """The history series of probe ``name`` a panel draws."""
    if kind in _SERIES:
        return [s.format(n=name) for s in _SERIES[kind] if s.format(n=name) in h]
    return [s for s in h if s == name or (s.startswith(name + "_") and kind == "delamination")]


def histories(study, p: dict, h: dict, qoi: dict, plots_dir) -> None:
    """histories.png: one panel per probe against time (ms); a check's reference dotted."""
    import matplotlib.pyplot as plt
    panels = [(n, k) for n, k in study.layout.names["probes"].items() if _series(n, k, h)]
    if not panels:
        return
    time = 1e3 * np.asarray(h["time"])
    cols = min(3, len(panels))
    rows = -(-len(panels) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.6 * rows), squeeze=False)
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    for ax, (name, kind) in zip(axes.flat, panels):
        unit, scale = _UNIT.get(kind, ("", 1.0))
        series = _series(name, kind, h)
        for s in sorted(series):
            ax.plot(time, scale * np.asarray(h[s]), label=s if len(series) > 1 else None)
        if f"no_fracture.{name}" in h:  # the all-FEM twin (case.no_fracture_reference)
            ax.plot(1e3 * np.asarray(h["no_fracture.time"]), scale * np.asarray(h[f"no_fracture.{name}"]), "k:",
                    label="no fracture (all-FEM)")
        for check, form in study.layout.names["checks"].items():
            if section(p, f"checks.{check}")["qoi"] in (f"peak_{name}", name):
                ref = CLOSED_FORMS[form].reference_qoi
                for key in (ref, ref + "_upper"):
                    if key in qoi:
                        ax.axhline(scale * qoi[key], color="k", ls=":" if key == ref else "--",
                                   label=key.replace("_", " "))
        what = {"flexural_cracks": " height", "debonding": "ed length", "impactor_motion": " velocity",
                "interface_damage": " area"}.get(kind, "")
        ax.set(xlabel="time (ms)", ylabel=f"{name.replace('_', ' ')}{what}" + (f" ({unit})" if unit else ""))
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(plots_dir / "histories.png", dpi=120)
    plt.close(fig)


def damage(h: dict, plots_dir) -> None:
    """damage_<t>us.png: particles (deformed), intralaminar bonds by damage (reds: 90 plies,
    oranges: 0 plies), interlaminar bonds by damage (blues; full colour = debonded); in 3D two
    x-z sections, mid-width (the symmetry plane) and the free edge."""
    import matplotlib.pyplot as plt
    for name in sorted({k.split(".")[0] for k in h if k.startswith("damage_") and "." in k}):
        x = 1e3 * np.asarray(h[f"{name}.x"])
        in_90 = np.asarray(h[f"{name}.in_90"]) > 0
        fem = 1e3 * np.asarray(h[f"{name}.fem_x"]) if f"{name}.fem_x" in h else None
        if f"{name}.width_index" in h:
            j = np.asarray(h[f"{name}.width_index"]).astype(int)
            y_edge = x[j == j.max(), 1].max()
            sections = [(j == 0, [0, 2], "y = 0 (symmetry plane)", 0.0),
                        (j == j.max(), [0, 2], f"y = {y_edge:.3g} mm (the zone's edge or the free edge)", y_edge)]
        else:
            sections = [(np.ones(len(x), bool), [0, 1], "", None)]
        wide = 12 if fem is None else 16
        legend = (": adhesive (blue) and cracks in the body (orange), darker = more damaged" if f"{name}.bonded" in h
                  else ": interlaminar (blue, particles and FEM node pairs) and intralaminar (red: 90 plies, "
                  "orange: 0 plies), darker = more damaged")
        fig, axes = plt.subplots(len(sections), 1, figsize=(wide, 3.2 * len(sections)), squeeze=False)
        for ax, (on, cols, label, plane) in zip(axes[:, 0], sections):
            if fem is not None:
                fem0 = 1e3 * np.asarray(h[f"{name}.fem_x0"])
                _far_field(ax, fem, fem0, np.asarray(h[f"{name}.fem_edges"]).astype(int), cols, plane)
                _far_field_bonds(ax, h, name, fem, fem0, cols, plane)
            _section(ax, h, name, x, in_90, on, cols)
            ax.set(xlabel="x (mm)", ylabel=f"{'yz'[cols[1] - 1]} (mm)",
                   title=f"damage at {name.split('_')[1]}" + (f", {label}" if label else legend)
                   + ("; FEM far field grey" if fem is not None else ""))
            ax.set_aspect("equal")
        fig.tight_layout()
        fig.savefig(plots_dir / f"{name}.png", dpi=120)
        plt.close(fig)


def _far_field(ax, fem, fem0, edges, cols, plane) -> None:
    """The FEM's deformed element edges (grey); in 3D those whose nodes lie, undeformed, in the
    node plane y nearest the section's (mm)."""
    from matplotlib.collections import LineCollection
    if plane is not None:
        ys = np.unique(fem0[:, 1])
        at = ys[np.argmin(np.abs(ys - plane))]
        on = np.abs(fem0[:, 1] - at) <= 1e-9 * max(np.ptp(fem0), 1.0)
        edges = edges[on[edges].all(axis=1)]
    ax.add_collection(LineCollection(fem[edges][:, :, cols], colors="0.75", linewidths=0.5))
    ax.autoscale()


def _far_field_bonds(ax, h, name, fem, fem0, cols, plane) -> None:
    """A cohesive far field's damaged node pairs (blues, as the zone's interlaminar bonds): a short
    tick across the interface at each pair; in 3D those in the section's node plane."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    key = f"{name}.fem_bond_nodes"
    if key not in h or not len(h[key]):
        return
    nodes, dmg = np.asarray(h[key]).astype(int), np.asarray(h[f"{name}.fem_bond_damage"])
    hit = dmg > 0.05
    if plane is not None:
        ys = np.unique(fem0[:, 1])
        hit &= np.abs(fem0[nodes, 1] - ys[np.argmin(np.abs(ys - plane))]) <= 1e-9 * max(np.ptp(fem0), 1.0)
    if not hit.any():
        return
    p = fem[nodes[hit]][:, cols]
    tick = 0.25 * np.ptp(fem0[:, cols[1]]) / max(8, len(np.unique(fem0[:, cols[1]])))
    segs = np.stack([p - [0, tick], p + [0, tick]], axis=1)
    ax.add_collection(LineCollection(segs, colors=plt.cm.Blues(0.3 + 0.7 * dmg[hit]), linewidths=1.5))


def _section(ax, h, name, x, in_90, on, cols) -> None:
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    ax.plot(x[on, cols[0]], x[on, cols[1]], ".", ms=1.5, color="0.7")
    for kind in ("intra", "inter"):
        pairs = np.asarray(h[f"{name}.{kind}_pairs"]).astype(int)
        dmg = np.asarray(h[f"{name}.{kind}_damage"])
        hit = (dmg > 0.05) & on[pairs].all(axis=1)
        if not hit.any():
            continue
        if kind == "inter":
            colors = plt.cm.Blues(0.3 + 0.7 * dmg[hit])
        else:
            ninety = in_90[pairs[hit]].all(axis=1)
            colors = np.where(ninety[:, None], plt.cm.Reds(0.3 + 0.7 * dmg[hit]), plt.cm.Oranges(0.3 + 0.7 * dmg[hit]))
        ax.add_collection(LineCollection(x[pairs[hit]][:, :, cols], colors=colors, linewidths=1.5))


def zone(h: dict, plots_dir) -> None:
    """zone.png: a growing zone's half width against time (ms), its conversions marked with the
    energy each changed (relative to the total)."""
    if "zone_half_width" not in h:
        return
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    ax.step(1e3 * np.asarray(h["time"]), 1e3 * np.asarray(h["zone_half_width"]), where="post", lw=1.2)
    for t, w, dE in zip(h.get("zone.conversion_time", []), h.get("zone.conversion_half_width", []),
                        h.get("zone.conversion_energy_jump", [])):
        ax.plot(1e3 * t, 1e3 * w, "o", ms=4, color="C1")
        ax.annotate(f"dE/E = {dE:.1e}", (1e3 * t, 1e3 * w), textcoords="offset points", xytext=(4, -10), fontsize=7)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("zone half width (mm)")
    ax.set_title("the damage zone as it grew")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(plots_dir / "zone.png", dpi=120)
    plt.close(fig)
