"""The simulation engine: SceneSpec (SI, :mod:`.spec`) -> Scene (pymunk objects, :mod:`.scene`,
optional physics from :mod:`.effects`) -> Simulation (stepping, impact recording, energy ledger
from :mod:`.energy`, state in SI, :mod:`.simulation`)."""

from perga.engine.energy import EnergyLedger
from perga.engine.machine import Scene, build_scene
from perga.engine.simulation import Impact, ImpactRecorder, Simulation
from perga.model.spec import (
    AirDragSpec,
    ChamberSpec,
    ContactSpec,
    DriveSpec,
    EffectsSpec,
    FloorFrictionSpec,
    GranuleSpec,
    HammerSpec,
    RotorSpec,
    SceneSpec,
)

__all__ = [
    "AirDragSpec",
    "ChamberSpec",
    "ContactSpec",
    "DriveSpec",
    "EffectsSpec",
    "EnergyLedger",
    "FloorFrictionSpec",
    "GranuleSpec",
    "HammerSpec",
    "Impact",
    "ImpactRecorder",
    "RotorSpec",
    "Scene",
    "SceneSpec",
    "Simulation",
    "build_scene",
]
