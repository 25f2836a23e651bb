"""Run output: CSV tables flushed as they grow, phase-locked recorders, summary.json."""
