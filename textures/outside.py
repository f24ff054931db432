"""Whether texture files may name files outside their own folder: ``--allow-outside`` on
the commands that load scenes, or ``FRICTEX_ALLOW_OUTSIDE=1`` in the environment (for a
whole process), or a batch job's own permission (:func:`allowing_outside`, for the thread
that runs the job).

By default a texture file names files (images, height maps, HaTT models, AHAP clips,
mode tables) in its own folder or below it (``textures.sections.files``). This module is
light (no numpy) so that the commands can add the option without loading the loader.
"""

from __future__ import annotations

import argparse
import os
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

from frictex.device.safe_text import escape_path

#: Setting this environment variable to 1 lets texture files name files outside their folder.
ALLOW_OUTSIDE_ENV = "FRICTEX_ALLOW_OUTSIDE"
HOW = f"pass --allow-outside or set {ALLOW_OUTSIDE_ENV}=1 to read it anyway"


#: a job's own permission, in the context (thread) running it: a Dask worker runs jobs of
#: several batches in threads of one process, which share one environment
_JOB_ALLOWS = ContextVar("frictex_job_allows_outside", default=False)


def outside_allowed() -> bool:
    """Whether files outside may be read here: the job running in this context allows it
    (:func:`allowing_outside`), or ``FRICTEX_ALLOW_OUTSIDE=1`` is set for the process."""
    return _JOB_ALLOWS.get() or os.environ.get(ALLOW_OUTSIDE_ENV, "").strip() == "1"


@contextmanager
def allowing_outside(allowed: bool):
    """Within it, in this context only, files outside may be read if ``allowed`` (a job's
    ``--allow-outside``); ``FRICTEX_ALLOW_OUTSIDE=1`` allows them whatever ``allowed``
    says. Other threads, which start with a context of their own, are not affected."""
    token = _JOB_ALLOWS.set(allowed)
    try:
        yield
    finally:
        _JOB_ALLOWS.reset(token)


class _AllowOutside(argparse.Action):
    """``--allow-outside``: sets ``FRICTEX_ALLOW_OUTSIDE=1`` for this run, so that every
    load of the scene sees it, in this process and in those it starts (the haptic
    process of the demo, the replays of a batch)."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=False, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        os.environ[ALLOW_OUTSIDE_ENV] = "1"
        setattr(namespace, self.dest, True)


def add_allow_outside(parser: argparse.ArgumentParser) -> None:
    """Add ``--allow-outside`` to a command that loads texture files."""
    parser.add_argument("--allow-outside", action=_AllowOutside,
                        help="let texture files name files outside their own folder (absolute "
                             "paths, '..', links leading out); only for files you trust (the "
                             "same as FRICTEX_ALLOW_OUTSIDE=1)")


def leads_out(base_dir: str | Path, name: str) -> str | None:
    """How ``name``, a path relative to the folder ``base_dir``, leads outside it (a
    phrase to follow the name: an absolute path, a '..' leading out, a symbolic link to
    a file outside), or None when it stays in the folder or below (links followed as far
    as they go)."""
    if os.path.isabs(name):
        return "is an absolute path"
    if os.path.normpath(name).split(os.sep)[0] == os.pardir:
        return "leads out of the folder through '..'"
    root = os.path.realpath(base_dir)
    real = os.path.realpath(os.path.join(base_dir, name))
    if os.path.commonpath([root, real]) != root:
        return f"passes through a symbolic link to {escape_path(Path(real))}, outside the folder"
    return None
