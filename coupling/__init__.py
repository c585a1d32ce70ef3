"""The orchestrator: case files, the coupled clock, scenes, outputs and the command line."""
import os

# One BLAS thread: the orchestrator's matrices are small, and OpenBLAS's second thread spins
# on the core an in-process engine or the LAMMPS worker needs (measured on beam_impact_3d_coarse:
# 24 s of system time in a 28 s run, 9 % slower). Set before numpy loads OpenBLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# The law kernels' OpenMP threads sleep between parallel regions instead of spinning on the
# core the engine, the FEM or the LAMMPS worker runs on next. Set before OpenMP loads.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
