"""Tuning a law's gains offline: Bayesian optimisation (Optuna's TPE, seeded) of the offline
loop's scores over a scenario set, each trial on a core of this machine or a worker of a Dask
cluster, as a map's points go (``parallel.compute``); ``drill_sim tune`` (msg_docs/control.md,
"Tuning the gains").

A trial is the law with some gains, run through ``drill_sim control``'s loop on every scenario
of the set; its objective (lower is better) is the mean over the scenarios of

    J = SSI + 10 · stick fraction + 10 · max(0, saturation − 0.05)

so sticking costs as much as an SSI ten times as large, and saturating the drive more than 5 %
of the time is penalised likewise. The reference tuning is the first trial, so the study
says plainly when nothing better was found. The study is kept in a journal file: an
interrupted ``drill_sim tune`` run again with the same file resumes it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from statistics import fmean

from ..control import LAWS, default_gains
from ..control.closed_loop import run_loop
from ..control.evaluation import LoopSettings, build_law, law_top_drive
from ..control.reference import reference_gains
from ..control.scenarios import named
from ..core import load_preset
from ..core.parameters import ParameterError
from . import parallel

STICK_WEIGHT, SATURATION_WEIGHT, SATURATION_FREE = 10.0, 10.0, 0.05
SPAN = 4.0               # default search range: the reference value / SPAN to x SPAN (log)
BETTER = 0.01            # a trial beats the reference if its objective is this much lower
DRIVE_LIMITS = ("torque_min_nm", "torque_max_nm")   # the drive's, not tuned


@dataclass(frozen=True)
class TrialJob:
    """One trial's work: the law with these gains on every scenario of the set."""

    preset: str
    law: str
    gains: Mapping[str, float]
    scenarios: tuple[str, ...]
    sample_period_s: float = 1e-3
    string_model: str = "lumped"
    sensor_profile: str = "ideal"
    sensor_seed: int = 0


@dataclass(frozen=True)
class TrialScore:
    objective: float                   # mean J over the scenarios (module docstring)
    ssi: float                         # means over the scenarios
    stick_fraction: float
    saturation_fraction: float


def score(job: TrialJob) -> TrialScore:
    """Run the trial (a module-level function: it travels to pool and Dask workers)."""
    preset = load_preset(job.preset)
    settings = LoopSettings(law=job.law, gains=dict(job.gains),
                            sample_period_s=job.sample_period_s,
                            string_model=job.string_model, sensor_profile=job.sensor_profile,
                            sensor_seed=job.sensor_seed)
    rows = [run_loop(preset, scenario, settings) for scenario in named(list(job.scenarios))]
    j = [r.ssi + STICK_WEIGHT * r.stick_fraction
         + SATURATION_WEIGHT * max(0.0, r.saturation_fraction - SATURATION_FREE) for r in rows]
    return TrialScore(fmean(j), fmean([r.ssi for r in rows]),
                      fmean([r.stick_fraction for r in rows]),
                      fmean([r.saturation_fraction for r in rows]))


@dataclass(frozen=True)
class Range:
    low: float
    high: float
    log: bool


def search_space(law: str, names: Sequence[str], reference: Mapping[str, float],
                 ranges: Mapping[str, tuple[float, float]]) -> dict[str, Range]:
    """Each gain's range: as given (``ranges``), else the reference value / SPAN to x SPAN on
    a log scale; a gain with neither is refused, naming what to give."""
    if law not in LAWS or not LAWS[law].GAINS:
        tunable = [n for n, c in LAWS.items() if c.GAINS]
        raise ParameterError(f"law {law!r} has no gains to tune: expected one of "
                             f"{', '.join(tunable)}")
    if not names:
        raise ParameterError(f"no gains to tune: expected --params with names of {law}'s "
                             f"gains ({', '.join(LAWS[law].GAINS)})")
    out = {}
    for name in names:
        if name not in LAWS[law].GAINS or name in DRIVE_LIMITS:
            tunable = [g for g in LAWS[law].GAINS if g not in DRIVE_LIMITS]
            raise ParameterError(f"{law} has no gain {name!r} to tune: expected one of "
                                 f"{', '.join(tunable)} (the torque limits are the drive's)")
        if name in ranges:
            low, high = ranges[name]
            if not (math.isfinite(low) and math.isfinite(high) and low < high):
                raise ParameterError(f"range of {name} = {low!r}:{high!r}: expected finite "
                                     "LOW < HIGH")
            out[name] = Range(low, high, low > 0.0 and high / low >= 10.0)
        elif reference.get(name, 0.0) > 0.0:
            v = float(reference[name])
            out[name] = Range(v / SPAN, v * SPAN, True)
        else:
            raise ParameterError(f"{name}: no reference value to centre its range on; give "
                                 f"it with --range {name}=LOW:HIGH")
    return out


def check_ends(job: TrialJob, space: Mapping[str, Range]) -> None:
    """Build the law at both ends of each gain's range (the others at ``job``'s gains), so a
    range the law refuses (a negative gain, a corner above what the sample period allows) is
    refused before any run, naming the range, not after the reference trial."""
    preset = load_preset(job.preset)
    drive = law_top_drive(preset, job.law, None)
    for name, r in space.items():
        for end in (r.low, r.high):
            settings = LoopSettings(law=job.law, gains={**job.gains, name: end},
                                    sample_period_s=job.sample_period_s,
                                    string_model=job.string_model,
                                    sensor_profile=job.sensor_profile)
            try:
                build_law(preset, settings, drive)
            except ParameterError as exc:
                raise ParameterError(f"range of {name} = {r.low:g}:{r.high:g}: the law refuses "
                                     f"{name} = {end:g} ({exc}); expected a range within the "
                                     "gain's") from None


@dataclass
class TuneResult:
    law: str
    reference_gains: dict[str, float]
    reference: TrialScore | None
    best_gains: dict[str, float]
    best: TrialScore
    trials: list[tuple[dict[str, float], TrialScore]] = field(default_factory=list)

    @property
    def improved(self) -> bool:
        """A trial scored clearly better than the reference gains: its objective lower by
        more than BETTER (1 %) of the reference's."""
        return self.reference is None or \
            self.best.objective < (1.0 - BETTER) * self.reference.objective


def tune(job: TrialJob, space: Mapping[str, Range], *, trials: int, journal: Path,
         seed: int = 0, workers: int = 1, scheduler: str | None = None,
         progress: Callable[[int, int], None] | None = None) -> TuneResult:
    """Run (or resume, from ``journal``) the study to ``trials`` finished trials."""
    import optuna
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        storage = JournalStorage(JournalFileBackend(str(journal)))
        study = optuna.create_study(study_name=f"drill_sim_tune_{job.law}", storage=storage,
                                    load_if_exists=True, direction="minimize",
                                    sampler=optuna.samplers.TPESampler(seed=seed))
    except (ValueError, KeyError, TypeError) as exc:     # a line that is not a journal's
        raise ParameterError(f"the study journal {journal} is damaged and cannot be resumed "
                             f"({type(exc).__name__}: {exc}); expected a journal this command "
                             "wrote: move it away, or give another --out") from None
    reference = {k: float(v) for k, v in job.gains.items()}
    settings = {k: (list(v) if isinstance(v, tuple) else v) for k, v in job.__dict__.items()
                if k != "gains"}
    searched = {name: [r.low, r.high, r.log] for name, r in space.items()}
    if not study.trials:                         # the reference first: the bar to beat
        study.set_user_attr("settings", settings)
        study.set_user_attr("space", searched)
        study.enqueue_trial({k: reference[k] for k in space})
    elif study.user_attrs.get("settings") != settings:
        raise ParameterError(f"the study in {journal} was run with other settings "
                             f"({study.user_attrs.get('settings')}); expected the same to resume "
                             "it, or another --out for a new study")
    elif study.user_attrs.get("space", searched) != searched:
        raise ParameterError(f"the study in {journal} searched other gains or ranges "
                             f"({study.user_attrs['space']}, now {searched}); expected the same "
                             "--params and --range to resume it, or another --out for a new "
                             "study")
    done = sum(t.state.is_finished() for t in study.trials)
    for t in study.trials:                       # trials an interruption left running
        if t.state == optuna.trial.TrialState.RUNNING:
            study.tell(t.number, state=optuna.trial.TrialState.FAIL)
    batch = max(1, workers)
    while done < trials:
        asked = [study.ask() for _ in range(min(batch, trials - done))]
        jobs = [TrialJob(**{**job.__dict__, "gains": {**reference, **{
            name: t.suggest_float(name, r.low, r.high, log=r.log)
            for name, r in space.items()}}}) for t in asked]
        for i, result in parallel.compute(jobs, workers=workers, scheduler=scheduler,
                                          fn=score):
            asked[i].set_user_attr("score", result.__dict__)
            study.tell(asked[i], result.objective)
            done += 1
            if progress is not None:
                progress(done, trials)
    return _result(study, job.law, reference, space)


def _result(study, law: str, reference: dict[str, float],
            space: Mapping[str, Range]) -> TuneResult:
    import optuna
    finished = [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE]
    table = [({**reference, **t.params}, TrialScore(**t.user_attrs["score"]))
             for t in finished if "score" in t.user_attrs]
    if not table:
        raise ParameterError("the study has no finished trial")
    ref = next((s for g, s in table if all(g[k] == reference[k] for k in space)), None)
    best_gains, best = min(table, key=lambda row: row[1].objective)
    return TuneResult(law, reference, ref, best_gains, best, table)


def reference_for(job: TrialJob) -> dict[str, float]:
    """The law's gains as ``drill_sim control`` runs it: its defaults (those given as numbers
    in its signature), then the reference tuning for the job's preset, string, sensors and
    sample period."""
    preset = load_preset(job.preset)
    defaults = {k: v for k, v in default_gains(job.law).items() if k not in DRIVE_LIMITS}
    return {**defaults, **reference_gains(
        job.law, preset, preset.top_drive.top_drive_inertia_kg_m2,
        string_model=job.string_model, sensor_profile=job.sensor_profile,
        sample_period_s=job.sample_period_s)}
