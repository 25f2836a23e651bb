"""The simulation engine: SceneSpec (SI, :mod:`.spec`) -> Scene (pymunk objects, :mod:`.scene`)
-> Simulation (stepping, impact recording, state in SI, :mod:`.simulation`)."""

from perga.engine.scene import Scene, build_scene
from perga.engine.simulation import Impact, ImpactRecorder, Simulation
from perga.engine.spec import ContactSpec, GranuleSpec, HammerSpec, RotorSpec, SceneSpec

__all__ = [
    "ContactSpec",
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
