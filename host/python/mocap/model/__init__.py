"""The body and the solver, as the Python tools use them: the solver wrapper and its
options, the PCA prior, the joint centres, calibration poses, exact observations of a
pose sequence (rigs, sites, sensor motion), robust triangulation and the choice of the
subject among the people a camera sees."""
