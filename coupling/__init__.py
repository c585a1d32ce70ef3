"""The orchestrator: case files, the coupled clock, scenes, outputs and the command line."""
import os

# One BLAS thread: the orchestrator's matrices are small, and OpenBLAS's second thread spins
# on the core an in-process engine or the LAMMPS worker needs (measured on beam_impact_3d_coarse:
# 24 s of system time in a 28 s run, 9 % slower). Set before numpy loads OpenBLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
