"""RC networks: declaration, parameters and the bilinear state space built from them."""

from rczone.network.disturbance import LatentForce
from rczone.network.network import CP_AIR, HeatInput, Node, RCNetwork, Resistor, SupplyAir
from rczone.network.parameters import Parameter
from rczone.network.prior import Prior
from rczone.network.statespace import BilinearStateSpace, LinearStateSpace, StateSpaceDerivative

__all__ = [
    "CP_AIR",
    "BilinearStateSpace",
    "HeatInput",
    "LatentForce",
    "LinearStateSpace",
    "Node",
    "Parameter",
    "Prior",
    "RCNetwork",
    "Resistor",
    "StateSpaceDerivative",
    "SupplyAir",
]
