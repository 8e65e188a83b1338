"""Demonstrator perturbations: one registry, one protocol (``base.Perturbation``), one module each.

``PERTURBATIONS`` maps a name to its class; every module of this package that defines one registers it, so
that ``colorsort-collect``'s flags, the recorded settings, ``colorsort-baseline``'s ``--demos.<name>`` flags,
cache folder names and shipped READMEs all come from the registry.
"""

from __future__ import annotations

import importlib
import pkgutil

from colorsort.data.perturbations.base import Hook, Perturbation, Step, perturbed
from colorsort.data.perturbations.registry import PERTURBATIONS, canonical, parse, register_perturbation

for _module in pkgutil.iter_modules(__path__):
    if _module.name not in ("base", "registry", "holds"):
        importlib.import_module(f"{__name__}.{_module.name}")

__all__ = ["PERTURBATIONS", "Hook", "Perturbation", "Step", "canonical", "parse", "perturbed", "register_perturbation"]
