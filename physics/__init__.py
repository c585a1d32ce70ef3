"""Physics both regions use: the interlaminar (Hashin) and intralaminar (Hoffman) laws and
failure criteria, law bonds between any two points (particles or FEM nodes) with their
compiled kernels, and rigid impactors in penalty contact. fem_region and dem_region import
this package and never each other."""
