"""The system a simulation is built from (:mod:`.spec`, mapped from a case by
:mod:`.from_case`), what it reports (:mod:`.records`: impacts, the energy ledger) and the
frames writers read (:mod:`.frame`). Plain data in SI units; never imports the engine, a
contact model or the output."""

from perga.model.frame import Frame, GranuleFrame, MachineFrame
from perga.model.records import EnergyLedger, HammerState, Impact, LedgerTerms
from perga.model.system import (
    AirDragSpec,
    ChamberSpec,
    ContactSpec,
    DrawingSpec,
    DriveSpec,
    EffectsSpec,
    FloorFrictionSpec,
    GranuleSpec,
    HammerSpec,
    RigidContactSpec,
    RotorSpec,
    SoftContactSpec,
    System,
)

__all__ = [
    "AirDragSpec",
    "ChamberSpec",
    "ContactSpec",
    "DrawingSpec",
    "DriveSpec",
    "EffectsSpec",
    "EnergyLedger",
    "FloorFrictionSpec",
    "Frame",
    "GranuleFrame",
    "GranuleSpec",
    "HammerSpec",
    "HammerState",
    "Impact",
    "LedgerTerms",
    "MachineFrame",
    "RigidContactSpec",
    "RotorSpec",
    "SoftContactSpec",
    "System",
]
