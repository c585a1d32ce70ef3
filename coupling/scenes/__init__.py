"""Scenes: builders that turn resolved case parameters into a Simulation (the verification
cases whose closed forms need their own code; every seed case is a study, coupling/study/).

A scene module declares NAME, DESCRIPTION, MODES (the modes it supports), PARAMETERS
(dotted key -> Param) and three functions:

- ``build(p, mode, dem) -> Simulation``: participants, interface and clock stages;
- ``evaluate(p, history, mode) -> (qoi, checks)``: quantities of interest, and checks against
  closed forms computed from ``p`` ({value, reference, rel_err, tol, passed, source});
- ``plot(p, history, qoi, plots_dir)``: the case's figures.
"""
from __future__ import annotations

from types import ModuleType

from . import (bar_wave, block_impact, bonded_block, cantilever, chain_consistency, chung_ooi, column_buckling, coupled_free_flight,
               coupled_vibration, dcb, enf, free_vibration, interface_patch, interface_wave, mixed_mode, ply_fracture)

Scene = ModuleType
SCENES: dict[str, Scene] = {m.NAME: m for m in (
    bar_wave, cantilever, free_vibration, column_buckling, block_impact,  # FEM far field
    chung_ooi.CHUNG_OOI_1, chung_ooi.CHUNG_OOI_2, chung_ooi.CHUNG_OOI_3,  # DEM back-end
    bonded_block.BONDED_BLOCK_MODULUS, bonded_block.BOND_STRENGTH, bonded_block.BONDED_BEAM_BENDING,
    chain_consistency, coupled_free_flight, interface_patch, interface_wave, coupled_vibration,  # coupling
    dcb, enf, mixed_mode, ply_fracture,  # damage physics
)}
