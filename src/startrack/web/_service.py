"""What the API and the pages both do: create jobs and batches, cancel, describe, save cameras.

One :class:`Service` per application holds the job store, the batch store and the worker pool.
Its methods raise :class:`~.refusals.Refusal` (or :class:`~.jobs.UnknownJobError`, a 404) for
every request it will not do; the API turns them into JSON, the pages into an error page.
"""

from __future__ import annotations

import json
from typing import Any

from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile

from ..errors import require
from ._analysis_jobs import validate_request
from ._batches import BatchStore, clean_name, folder_images
from ._config import WebConfig
from ._jobs import TERMINAL, JobStore, new_id, write_json
from ._options import PROFILE_NAME, OptionError, camera_from_json, camera_to_json
from ._refusals import Refusal
from ._runner import QueueFullError, WorkerPool
from ._simulation import validate_simulation
from ._uploads import StoredImage, copy_local, store_upload

RETRY_AFTER_S = 10


def option_refusal(exc: OptionError) -> Refusal:
    return Refusal(422, str(exc), exc.field)


class Service:
    """The jobs, batches and workers of one server (module docstring)."""

    def __init__(self, config: WebConfig):
        self.config = config
        self.jobs = JobStore(config.jobs_dir)
        self.batches = BatchStore(config.batches_dir)
        config.cameras_dir.mkdir(parents=True, exist_ok=True)
        self.pool = WorkerPool(self.jobs, config.workers, config.time_limit_s, config.max_queued, config.prewarm)

    def start(self) -> None:
        self.pool.start(self.jobs.recover())

    def stop(self) -> None:
        self.pool.stop()

    # --- admission ----------------------------------------------------------------------------
    def check_room(self, n_jobs: int = 1) -> None:
        """429 unless ``n_jobs`` more jobs fit in the queue."""
        info = self.pool.info()
        if info["queued"] + n_jobs > info["max_queued"]:
            raise Refusal(429, f"the queue is full: {info['queued']} of {info['max_queued']} jobs waiting, "
                               f"{n_jobs} more asked; try again later", headers={"Retry-After": str(RETRY_AFTER_S)})

    def _submit(self, job_id: str) -> None:
        try:
            self.pool.submit(job_id)
        except QueueFullError as exc:
            self.jobs.set_state(job_id, state="cancelled", error=str(exc))
            raise Refusal(429, str(exc), headers={"Retry-After": str(RETRY_AFTER_S)}) from None

    # --- solve jobs ---------------------------------------------------------------------------
    def _new_job(self, stored: StoredImage, job_id: str, options: dict, batch: str | None) -> None:
        self.jobs.create("solve", {"label": stored.label, "input": stored.path.name, "format": stored.format,
                                   "sha256": stored.sha256, "bytes": stored.n_bytes, "width": stored.width,
                                   "height": stored.height, "options": options, "batch": batch,
                                   "simulate": None}, job_id)

    async def create_job(self, upload: UploadFile, options: dict) -> dict[str, Any]:
        """One solve job for an uploaded file (checked: 415, 422), queued."""
        [job_id] = await self._store_all([upload], options, None)
        self._submit(job_id)
        return {"id": job_id, "state": "queued"}

    async def _store_all(self, uploads: list[UploadFile], options: dict, batch: str | None) -> list[str]:
        """Store every upload in its own job folder; if one is refused, none is kept."""
        done: list[tuple[str, StoredImage | None]] = []
        try:
            for upload in uploads:
                job_id, folder = self.jobs.reserve()
                done.append((job_id, None))
                stored = await run_in_threadpool(store_upload, upload, folder, "input", self.config.max_pixels)
                done[-1] = (job_id, stored)
        except Refusal:
            for job_id, _ in done:
                self.jobs.discard(self.jobs.root / job_id)
            raise
        for job_id, kept in done:
            self._new_job(require(kept, "a stored upload"), job_id, options, batch)
        return [job_id for job_id, _ in done]

    def create_simulated(self, params: Any, options: dict) -> dict[str, Any]:
        """A solve job whose input the worker renders first (:mod:`._simulation`)."""
        try:
            scene = validate_simulation(params)
        except OptionError as exc:
            raise option_refusal(exc) from None
        job_id, _ = self.jobs.reserve()
        self.jobs.create("solve", {"label": f"simulated (seed {scene['seed']})", "input": "input.fits",
                                   "format": "fits", "sha256": None, "bytes": None, "width": scene["width"],
                                   "height": scene["height"], "options": options, "batch": None,
                                   "simulate": scene}, job_id)
        self._submit(job_id)
        return {"id": job_id, "state": "queued"}

    async def create_batch(self, uploads: list[UploadFile], options: dict, name: str | None) -> dict[str, Any]:
        """A batch of uploaded files (all checked before any job is queued)."""
        if not uploads:
            raise Refusal(400, "a batch needs one or more 'file' parts, or a 'folder' under --root")
        self.check_room(len(uploads))
        batch_id = new_id()
        ids = await self._store_all(uploads, options, batch_id)
        return self._queue_batch(batch_id, ids, name or f"{len(ids)} uploaded images", {"kind": "upload"})

    async def create_folder_batch(self, relative: str, options: dict, name: str | None) -> dict[str, Any]:
        """A batch of the image files of a folder under ``--root``."""
        folder, paths, skipped = folder_images(self.config.root, relative)
        self.check_room(len(paths))
        batch_id, ids = new_id(), []
        try:
            for path in paths:
                job_id, job_folder = self.jobs.reserve()
                ids.append(job_id)
                stored = await run_in_threadpool(copy_local, path, job_folder, "input", self.config.max_pixels)
                self._new_job(stored, job_id, options, batch_id)
        except Refusal:
            for job_id in ids:
                self.jobs.discard(self.jobs.root / job_id)
            raise
        root = require(self.config.root, "the server's folder root")
        source = {"kind": "folder", "folder": str(folder.relative_to(root)), "skipped": skipped}
        return self._queue_batch(batch_id, ids, name or folder.name or "root", source)

    def _queue_batch(self, batch_id: str, ids: list[str], name: str, source: dict) -> dict[str, Any]:
        self.batches.create(clean_name(name), ids, source, batch_id)
        for job_id in ids:
            self._submit(job_id)
        return {"id": batch_id, "jobs": ids, "state": "queued", "skipped": source.get("skipped", [])}

    # --- analysis jobs ------------------------------------------------------------------------
    def create_analysis(self, body: Any) -> dict[str, Any]:
        request = validate_request(body, self.jobs, self.batches)
        self.check_room()
        label = f"{request['analysis']} over {', '.join(s['name'] for s in request['sets'])}"
        job_id = self.jobs.create("analysis", {"label": label[:120], "analysis": request, "options": {},
                                               "input": None, "batch": None})
        self._submit(job_id)
        return {"id": job_id, "state": "queued"}

    # --- cancel, remove -----------------------------------------------------------------------
    def cancel_or_remove(self, job_id: str) -> dict[str, Any]:
        """Cancel a queued or running job; remove a finished one."""
        state = self.jobs.state(job_id)["state"]
        if state in TERMINAL:
            self.jobs.delete(job_id)
            return {"id": job_id, "deleted": True}
        return {"id": job_id, "state": self.pool.cancel(job_id)}

    # --- views --------------------------------------------------------------------------------
    def job_view(self, job_id: str) -> dict[str, Any]:
        """The JSON of ``GET /api/jobs/{id}``."""
        meta, state = self.jobs.meta(job_id), self.jobs.state(job_id)
        folder = self.jobs.folder(job_id)
        result = json.loads((folder / "result.json").read_text()) if (folder / "result.json").is_file() else None
        files = self.jobs.files(job_id)
        return {"id": job_id, "kind": meta["kind"], "label": meta.get("label"), "state": state["state"],
                "stage": state.get("stage"), "progress": state.get("progress", 0.0), "error": state.get("error"),
                "result": result, "files": {name: f"/api/jobs/{job_id}/files/{name}" for name in files},
                "times_s": state.get("times_s", {}), "created": meta["created"], "started": state.get("started"),
                "finished": state.get("finished"), "queue_position": self.pool.queue_position(job_id),
                "batch": meta.get("batch"), "options": meta.get("options"), "simulate": meta.get("simulate"),
                "analysis": meta.get("analysis"), "input": {k: meta.get(k) for k in ("format", "sha256", "bytes",
                                                                                     "width", "height")},
                "page": f"/jobs/{job_id}"}

    def job_summary(self, job_id: str) -> dict[str, Any]:
        """One line of ``GET /api/jobs``."""
        view = self.job_view(job_id)
        result = view["result"] or {}
        return {k: view[k] for k in ("id", "kind", "label", "state", "stage", "progress", "error", "created",
                                     "batch", "page")} | {
            "status": result.get("status"), "n_detected": result.get("n_detected"),
            "n_matched": result.get("n_matched"), "residual_arcsec": result.get("residual_arcsec"),
            "total_s": sum((view["times_s"] or {}).values()) or None}

    def batch_view(self, batch_id: str) -> dict[str, Any]:
        batch = self.batches.get(batch_id)
        jobs = [self.job_summary(j) for j in batch["jobs"] if (self.jobs.root / j / "job.json").is_file()]
        counts: dict[str, int] = {}
        for job in jobs:
            counts[job["state"]] = counts.get(job["state"], 0) + 1
        finished = all(job["state"] in TERMINAL for job in jobs)
        return {**batch, "jobs": jobs, "counts": counts, "finished": finished, "page": f"/batches/{batch_id}"}

    # --- cameras ------------------------------------------------------------------------------
    def save_camera(self, body: Any) -> dict[str, Any]:
        """Save a camera profile (``name`` + the fields of :class:`startrack.camera.Camera`)."""
        from ..camera import PRESETS, preset_key

        if not isinstance(body, dict):
            raise Refusal(422, "the body must be a JSON object: name and the camera's fields", "body")
        fields = dict(body)
        name = fields.pop("profile", None) or fields.get("name")
        if not isinstance(name, str) or not PROFILE_NAME.match(name) or preset_key(name) in PRESETS:
            raise Refusal(422, f"name must be 1-64 letters, digits, '.', '_' or '-' and not a preset, got {name!r}",
                          "name")
        try:
            camera = camera_from_json({**fields, "name": name}, "camera")
        except OptionError as exc:
            raise option_refusal(exc) from None
        write_json(self.config.cameras_dir / f"{name}.json", camera_to_json(camera))
        return {"name": name, "camera": camera_to_json(camera)}
