"""The analytical models: the paper as published, the physically consistent models, impact laws
and contact calibration."""
