"""rczone: control-oriented grey-box RC thermal models of building zones.

Declare an RC network, build its bilinear state space, simulate it exactly, compare
model orders, and identify R and C from data.
"""

__version__ = "0.1.0"
