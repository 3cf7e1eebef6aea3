"""Dynamics models: quadrotor allocation and rotors, tethered and planar models."""

from tetherland.models.quadrotor import RotorLayout

__all__ = ["RotorLayout"]
