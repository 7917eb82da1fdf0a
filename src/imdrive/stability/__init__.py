"""Stability maps of the sensorless drive: steady state, small-signal model, maps."""
