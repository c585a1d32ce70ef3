"""Participants and their assembly into one run.

Each participant has the same small lifecycle: build (from a mesh or a scene), a stable step,
advance, read and write the transition interface, checkpoint / restore, finalize.

- fem.py: the FEM far field (fem_region.ExplicitDynamics) and a run of it alone;
- dem.py: an engine with the coupling layer's models on its particles, and a run of it alone;
- clock.py: the coupled step (impulse multiple time stepping), its named stages in order;
- coupled.py: FEM + engine + transition interface + tie assembled into one Simulation.
"""
