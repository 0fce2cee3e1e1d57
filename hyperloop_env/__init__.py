"""hyperloop-suspension-gym: simulator and RL benchmark for hyperloop magnetic suspension."""

__version__ = "0.1.0"
