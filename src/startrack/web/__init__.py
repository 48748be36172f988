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

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "create_app": ".app",
    "DEFAULT_MAX_QUEUED": ".config",
    "DEFAULT_MAX_UPLOAD_MB": ".config",
    "DEFAULT_PORT": ".config",
    "DEFAULT_TIME_LIMIT_S": ".config",
    "WebConfig": ".config",
    "default_data_dir": ".config",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
