"""perga: bee-bread granules struck by hammers on a rotor, simulated and checked against theory."""

__version__ = "0.1.0"
