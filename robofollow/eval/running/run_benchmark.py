"""The benchmark a run's episodes come from: the release it names; for a run made before runs
named their release, the first release frozen from its specs; for a run of a working compile
(--specs), those specs compiled again. What resuming, merging, reporting and reproducing a
run read, so that a run is always read on the test set it was made on."""

from __future__ import annotations

from pathlib import Path

from robofollow import release
from robofollow.compiled_cache import Episodes
from robofollow.errors import RoboFollowError
from robofollow.eval.running.runner import EvalOptions


class RunBenchmarkError(RoboFollowError):
    """A run whose benchmark is not here, or is not the one asked for."""


def run_release(options: EvalOptions) -> str | None:
    """The release a run was made on (None: a working compile's run, or specs no release was
    frozen from)."""
    if options.specs is not None:
        return None
    return options.release or release.of_spec_digest(options.spec_digest)


def described(options: EvalOptions) -> str:
    """The run's benchmark in words: 'release v1 (digest 30bc9fa66a2e)' or 'a working compile of
    SPECS (spec digest cae10a3dc698), not a release'."""
    name = run_release(options)
    if name is not None:
        digest = options.release_digest or release.manifest(name).digest
        return f"release {name} (digest {digest[:12]})"
    where = f" of {options.specs}" if options.specs else ""
    return (f"a working compile{where} (spec digest {options.spec_digest[:12]}), not a "
            "release")


def run_benchmark(run: Path, options: EvalOptions, name: str | None = None,
                  specs: Path | None = None) -> Episodes:
    """The benchmark of `run` (made with `options`): its release, or the working compile it
    names. `name` (--release) must be the run's own; `specs` (--specs) reads a working
    compile instead, which must be of the run's specs."""
    if specs is not None:
        benchmark = release.benchmark(specs=specs)
        if benchmark.spec.digest != options.spec_digest:
            raise RunBenchmarkError(f"{run} was made on other specs than {specs} (spec digest "
                                    f"{options.spec_digest[:12]}, not "
                                    f"{benchmark.spec.digest[:12]})")
        return benchmark
    own = run_release(options)
    if own is None:
        recorded = Path(options.specs) if options.specs else None
        if recorded is None or not recorded.exists():
            where = f" of {options.specs}" if options.specs else ""
            raise RunBenchmarkError(f"{run} was made on a working compile{where}, not a "
                                    "release: --specs SPECS names its specs")
        return run_benchmark(run, options, specs=recorded)
    if name is not None and name != own:
        raise RunBenchmarkError(f"{run} was made on release {own}, not {name}: a run is read "
                                "on its own release (leave out --release)")
    try:
        benchmark = release.load(own)
    except release.ReleaseError as error:
        raise RunBenchmarkError(f"{run} was made on release {own}: {error}") from None
    if benchmark.spec.digest != options.spec_digest:
        raise RunBenchmarkError(f"{run} names release {own}, but its spec digest "
                                f"{options.spec_digest[:12]} is not the release's")
    return benchmark
