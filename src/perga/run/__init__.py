"""``perga run``: a case into a run directory, whatever happens.

The loop (:mod:`.loop`: the simulation stepped to where its writers, progress reports and
checkpoints fall due), the run directory (:mod:`.directory`), the guards every frame passes
(:mod:`.guards`), summary.json (:mod:`.summary`), checkpoints (:mod:`.checkpoints`), going on
from another run (:mod:`.restart`: ``--resume``, ``--from``) and the command's request
(:mod:`.request`)."""

from perga.run.directory import prepare_directory
from perga.run.guards import RunStoppedError
from perga.run.loop import resume_run, run_case, simulate
from perga.run.summary import COMPLETED, FINISHED, LEDGER_OFF, RunSummary

__all__ = [
    "COMPLETED",
    "FINISHED",
    "LEDGER_OFF",
    "RunStoppedError",
    "RunSummary",
    "prepare_directory",
    "resume_run",
    "run_case",
    "simulate",
]
