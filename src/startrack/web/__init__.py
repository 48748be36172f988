"""The browser tool, ``startrack web``: a local server over the library with pages and a JSON API.

Nothing here computes anything the library does not: a job reads an upload, detects, identifies
and fits with :mod:`startrack.detect`, :mod:`startrack.solve` and :mod:`startrack.calibrate`, draws
the annotated frame and writes the result files; an analysis job calls
:func:`startrack.analysis.postprocess.run_analysis`. Modules:

- :mod:`.config` the server's settings (:class:`WebConfig`);
- :mod:`.jobs` the job store on disk (one folder per job) and its state machine;
- :mod:`.runner` the bounded pool of worker processes (time limit, cancellation, crashes);
- :mod:`.pipeline` what a worker does for one solve job, stage by stage; :mod:`.presets` the
  detection presets (``auto`` included); :mod:`.rejects` the spots the detector refused and why;
  :mod:`.annotate` the annotated frame; :mod:`.outputs` the result files; :mod:`.records` the
  solution kept on disk and the :class:`~startrack.analysis.records.ImageRecord` rebuilt from it;
  :mod:`.analysis_jobs` analysis jobs over result sets;
- :mod:`.options` validation of a job's ``options`` JSON; :mod:`.uploads` streaming uploads with
  their size limit, content sniffing and dimension check; :mod:`.batches` result sets (several
  files, or a folder under ``--root``);
- :mod:`.api` the JSON API, :mod:`.pages` the HTML pages, :mod:`.schema` the OpenAPI document,
  :mod:`.app` the Starlette application.

See ``docs/web.md``.
"""

from __future__ import annotations

from .config import WebConfig

__all__ = ["WebConfig", "create_app"]


def create_app(config: WebConfig):
    """The Starlette application for ``config`` (see :func:`startrack.web.app.create_app`)."""
    from .app import create_app as _create

    return _create(config)
