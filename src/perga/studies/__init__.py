"""Studies built on the models: the paper check, later sweeps, calibration and accuracy."""
