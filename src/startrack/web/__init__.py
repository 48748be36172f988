"""The browser tool, ``startrack web``: a local server over the library with pages and a JSON API.

Nothing here computes anything the library does not: a job reads an upload, detects, identifies
and fits with :mod:`startrack.detect`, :mod:`startrack.solve` and :mod:`startrack.calibrate`, draws
the annotated frame and writes the result files; an analysis job calls
:func:`startrack.analysis.postprocess.run_analysis`. Modules:

- :mod:`._config` the server's settings (:class:`WebConfig`);
- :mod:`._jobs` the job store on disk (one folder per job) and its state machine;
- :mod:`._runner` the bounded pool of worker processes (time limit, cancellation, crashes);
- :mod:`._pipeline` what a worker does for one solve job, stage by stage; :mod:`._presets` the
  detection presets (``auto`` included); :mod:`._rejects` the spots the detector refused and why;
  :mod:`._annotate` the annotated frame; :mod:`._outputs` the result files; :mod:`._records` the
  solution kept on disk and the :class:`~startrack.analysis._records.ImageRecord` rebuilt from it;
  :mod:`._analysis_jobs` analysis jobs over result sets;
- :mod:`._options` validation of a job's ``options`` JSON; :mod:`._uploads` streaming uploads with
  their size limit, content sniffing and dimension check; :mod:`._batches` result sets (several
  files, or a folder under ``--root``);
- :mod:`._api` the JSON API, :mod:`._pages` the HTML pages, :mod:`._schema` the OpenAPI document,
  :mod:`._app` the Starlette application.

See ``docs/web.md``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._app import create_app
    from ._config import (
        DEFAULT_MAX_QUEUED,
        DEFAULT_MAX_UPLOAD_MB,
        DEFAULT_PORT,
        DEFAULT_TIME_LIMIT_S,
        WebConfig,
        default_data_dir,
    )

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
