"""A tiny sweep the store and resume tests share: 3 x 2 sensorless drives of 4 ms."""

TINY = """
name = "tiny"
base = "sensorless"
chunk_size = 2
window_s = 0.002

[set]
simulation.t_end_s = 0.004

[axes]
R2_ratio = [0.8, 1.0, 1.2]
load_Nm = [0.0, 2.0]
"""
