// startrack web: live progress of jobs and result sets, zoom and pan of figures. Our own code, no library.
"use strict";

const TERMINAL = new Set(["done", "failed", "cancelled"]);

function pollJob(section) {
  const id = section.dataset.job;
  const fill = document.getElementById("progress-fill");
  const badge = document.getElementById("job-state");
  async function tick() {
    let job;
    try {
      const response = await fetch(`/api/jobs/${id}`, {cache: "no-store"});
      if (!response.ok) return;
      job = await response.json();
    } catch (err) {
      setTimeout(tick, 1000);  // the server is busy or restarting: try again
      return;
    }
    fill.style.width = `${(job.progress * 100).toFixed(1)}%`;
    badge.textContent = job.state;
    badge.className = `state state-${job.state}`;
    for (const li of section.querySelectorAll("li[data-stage]")) {
      const stage = li.dataset.stage;
      const time = job.times_s[stage];
      li.className = stage === job.stage ? "current" : (time !== undefined ? "done" : "");
      li.querySelector(".time").textContent = time !== undefined ? `${time.toFixed(3)} s` : "";
    }
    const position = document.getElementById("queue-position");
    if (position) position.textContent = job.queue_position ? `number ${job.queue_position} in the queue` : "";
    if (TERMINAL.has(job.state)) {
      window.location.reload();
    } else {
      setTimeout(tick, 400);
    }
  }
  tick();
}

function pollBatch(section) {
  const id = section.dataset.batch;
  async function tick() {
    try {
      const response = await fetch(`/api/batches/${id}`, {cache: "no-store"});
      const batch = await response.json();
      document.getElementById("batch-counts").textContent =
        Object.entries(batch.counts).map(([state, n]) => `${n} ${state}`).join(", ");
      if (batch.finished) { window.location.reload(); return; }
    } catch (err) { /* try again below */ }
    setTimeout(tick, 700);
  }
  tick();
}

// Zoom about the cursor with the wheel, pan by dragging, double-click to fit.
function zoomable(root) {
  const view = root.querySelector(".zoom-view");
  const img = view.querySelector("img");
  let scale = 1, x = 0, y = 0, drag = null;
  function apply() {
    scale = Math.min(Math.max(scale, 1), 16);
    const maxX = 0, minX = view.clientWidth * (1 - scale);
    const maxY = 0, minY = img.clientHeight * (1 - scale);
    x = Math.min(maxX, Math.max(minX, x));
    y = Math.min(maxY, Math.max(minY, y));
    img.style.transform = `translate(${x}px, ${y}px) scale(${scale})`;
    root.dataset.scale = scale.toFixed(3);
  }
  function zoomAt(factor, cx, cy) {
    const next = Math.min(Math.max(scale * factor, 1), 16);
    x = cx - (cx - x) * next / scale;
    y = cy - (cy - y) * next / scale;
    scale = next;
    apply();
  }
  view.addEventListener("wheel", (event) => {
    event.preventDefault();
    const box = view.getBoundingClientRect();
    zoomAt(event.deltaY < 0 ? 1.25 : 0.8, event.clientX - box.left, event.clientY - box.top);
  }, {passive: false});
  view.addEventListener("pointerdown", (event) => {
    drag = {px: event.clientX, py: event.clientY, x, y};
    view.setPointerCapture(event.pointerId);
    view.classList.add("dragging");
  });
  view.addEventListener("pointermove", (event) => {
    if (!drag) return;
    x = drag.x + event.clientX - drag.px;
    y = drag.y + event.clientY - drag.py;
    apply();
  });
  const stop = () => { drag = null; view.classList.remove("dragging"); };
  view.addEventListener("pointerup", stop);
  view.addEventListener("pointercancel", stop);
  view.addEventListener("dblclick", () => { scale = 1; x = 0; y = 0; apply(); });
  const centre = () => [view.clientWidth / 2, view.clientHeight / 2];
  root.querySelector("[data-zoom-in]").addEventListener("click", () => zoomAt(1.5, ...centre()));
  root.querySelector("[data-zoom-out]").addEventListener("click", () => zoomAt(1 / 1.5, ...centre()));
  root.querySelector("[data-zoom-reset]").addEventListener("click", () => { scale = 1; x = 0; y = 0; apply(); });
}

// Show the parameters of the chosen analysis only.
function analysisForm(select) {
  const show = () => {
    for (const block of document.querySelectorAll(".analysis-params")) {
      block.classList.toggle("shown", block.dataset.analysis === select.value);
    }
  };
  select.addEventListener("change", show);
  show();
}

document.addEventListener("DOMContentLoaded", () => {
  const progress = document.getElementById("progress");
  if (progress && !TERMINAL.has(progress.dataset.state)) pollJob(progress);
  const batch = document.getElementById("batch-progress");
  if (batch && batch.dataset.finished === "no") pollBatch(batch);
  for (const root of document.querySelectorAll("[data-zoom]")) zoomable(root);
  const select = document.getElementById("analysis-select");
  if (select) analysisForm(select);
});
