"""Blind, independent test rig for the thrustshape motor-model checker (own physics, loggers, draws)."""
