// The review page (/review/{session}): the session's metrics (T, NFC, the three answers), the
// same per trainer with how much the trainers agree, its episodes with returns and a replay on
// the canvas, every query's answer, who gave it and its latency on a timeline, and the
// recording for the Rerun viewer.

import { ApiError, download, getJson, getToken, setToken } from "./api.js";
import { notify } from "./notify.js";
import { linePlot } from "./plot.js";
import { drawScene } from "./render.js";
import { buildStage, onResize } from "./stage.js";

const $ = (id) => document.getElementById(id);
const sessionId = decodeURIComponent(location.pathname.split("/").filter(Boolean)[1] || "");
const SURVEY_WORDS = { overall_experience: "Overall experience", perceived_intelligence: "Perceived intelligence", cognitive_ease: "Cognitive ease" };

const replay = { clip: null, views: [], index: 0, playing: false, speed: 1, fps: 20, last: 0, acc: 0, episode: null };

function text(tag, content, cls) {
  const e = document.createElement(tag);
  e.textContent = content;
  if (cls) e.className = cls;
  return e;
}

function metric(dl, label, value) {
  const d = document.createElement("div");
  d.append(text("dt", label), text("dd", value));
  dl.append(d);
}

function valueWords(v) {
  if (v && typeof v === "object" && v.tally) {
    return Object.entries(v.tally).filter(([, n]) => n > 0).map(([k, n]) => `${n}× ${k}`).join(", ");
  }
  if (typeof v === "number" && !Number.isInteger(v)) return `${v.toFixed(2)} (mean)`;
  return { 1: "+1 good", 0: "0 no feedback", "-1": "−1 bad", left: "left", right: "right", equal: "about equal", skip: "skip" }[String(v)] ?? String(v);
}

const MEASURES = { krippendorff_alpha_ordinal: "Krippendorff's α (ordinal)", fleiss_kappa: "Fleiss' κ" };

function showTrainers(trainers, agreement) {
  const tbody = document.querySelector("#trainers tbody");
  const surveyWords = (s) => (s ? `${s.overall_experience} / ${s.perceived_intelligence} / ${s.cognitive_ease}` : "–");
  tbody.replaceChildren(
    ...trainers.map((t) => {
      const tr = document.createElement("tr");
      tr.dataset.trainer = t.name ?? "";
      tr.append(
        text("td", t.name ?? "anonymous"),
        text("td", String(t.answers), "num"),
        text("td", String(t.no_feedback), "num"),
        text("td", t.trainer_seconds == null ? "–" : `${t.trainer_seconds.toFixed(1)} s`, "num"),
        text("td", t.latency_ms_median == null ? "–" : `${(t.latency_ms_median / 1000).toFixed(2)} s`, "num"),
        text("td", surveyWords(t.survey)),
      );
      return tr;
    }),
  );
  $("trainers-empty").classList.toggle("hidden", trainers.length > 0);
  const box = $("agreement");
  if (!agreement) {
    box.textContent = "";
    return;
  }
  const measure = MEASURES[agreement.measure] ?? agreement.measure;
  box.replaceChildren();
  if (agreement.value == null) {
    box.append(`Agreement (${measure}): not defined yet (${agreement.units} quer${agreement.units === 1 ? "y" : "ies"} answered by two or more trainers).`);
  } else {
    box.append(`Agreement (${measure}): `, Object.assign(document.createElement("strong"), { id: "agreement-value", textContent: agreement.value.toFixed(3) }), ` over ${agreement.units} quer${agreement.units === 1 ? "y" : "ies"} answered by two or more trainers.`);
  }
  document.body.dataset.agreement = agreement.value == null ? "" : String(agreement.value);
  const pairs = document.querySelector("#pairs tbody");
  pairs.replaceChildren(
    ...agreement.pairs.map((p) => {
      const tr = document.createElement("tr");
      tr.append(text("td", `${p.a_name} · ${p.b_name}`), text("td", String(p.units), "num"), text("td", p.value == null ? "–" : p.value.toFixed(3), "num"));
      return tr;
    }),
  );
  $("pairs").classList.toggle("hidden", agreement.pairs.length === 0);
}

// ---- replay ---------------------------------------------------------------------------------

function drawReplay() {
  if (!replay.clip) return;
  const frames = replay.clip.frames;
  const i = Math.max(0, Math.min(frames.length - 1, replay.index));
  for (const { canvas, view } of replay.views) {
    drawScene(canvas, replay.clip.geometry, frames[i], view, { trail: frames.slice(Math.max(0, i - 60), i + 1) });
  }
  $("scrub").value = String(i);
  $("frame-no").textContent = `${i + 1} / ${frames.length}`;
  document.body.dataset.replayFrame = String(i);
}

function setPlaying(on) {
  replay.playing = on && !!replay.clip;
  $("play").querySelector("span").textContent = replay.playing ? "Pause" : "Play";
  document.body.dataset.replay = replay.playing ? "playing" : "paused";
  replay.last = performance.now();
  replay.acc = 0;
}

function stepBy(n) {
  if (!replay.clip) return;
  setPlaying(false);
  replay.index = Math.max(0, Math.min(replay.clip.frames.length - 1, replay.index + n));
  drawReplay();
}

function tick(now) {
  if (replay.playing && replay.clip) {
    replay.acc += ((now - replay.last) / 1000) * replay.fps * replay.speed;
    const n = Math.floor(replay.acc);
    if (n > 0) {
      replay.acc -= n;
      replay.index += n;
      if (replay.index >= replay.clip.frames.length - 1) {
        replay.index = replay.clip.frames.length - 1;
        setPlaying(false);
      }
      drawReplay();
    }
  }
  replay.last = now;
  requestAnimationFrame(tick);
}

async function loadEpisode(e, tr) {
  $("replay-title").textContent = `episode ${e.episode}: loading…`;
  let clip;
  try {
    clip = await getJson(`/api/sessions/${encodeURIComponent(sessionId)}/episodes/${e.episode}/frames`);
  } catch (err) {
    const why = err instanceof ApiError && err.status === 404 ? `${err.message} (the server keeps no frames for this episode)` : err.message;
    $("replay-title").textContent = `episode ${e.episode} cannot be replayed`;
    $("replay-info").textContent = `Replay failed: ${why}. The recording below holds every step.`;
    notify(`Episode ${e.episode} cannot be replayed: ${why}`, { kind: "error" });
    return;
  }
  for (const r of document.querySelectorAll("#episodes tr.playing")) r.classList.remove("playing");
  tr.classList.add("playing");
  replay.clip = clip;
  replay.episode = e.episode;
  replay.index = 0;
  replay.views = buildStage($("replay-stage"), clip.geometry);
  $("replay-empty").classList.add("hidden");
  $("replay-title").textContent = `episode ${e.episode}: return ${e.return.toFixed(1)}, ${e.outcome}`;
  $("replay-info").textContent = "Keys: K play/pause, ← → step one frame.";
  $("scrub").max = String(clip.frames.length - 1);
  for (const id of ["play", "back", "fwd", "speed", "scrub"]) $(id).disabled = false;
  document.body.dataset.replayEpisode = String(e.episode);
  drawReplay();
  setPlaying(true);
}

// ---- page -----------------------------------------------------------------------------------

function timeline(answers) {
  const box = $("timeline");
  if (!answers.length) {
    box.replaceChildren();
    return;
  }
  const NS = "http://www.w3.org/2000/svg";
  const W = 900;
  const H = 90;
  const t = answers.map((a) => Date.parse(a.asked_at));
  const t0 = Math.min(...t);
  const t1 = Math.max(...answers.map((a) => Date.parse(a.answered_at)), t0 + 1);
  const X = (v) => 30 + ((v - t0) / (t1 - t0)) * (W - 60);
  const svg = document.createElementNS(NS, "svg");
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  svg.setAttribute("role", "img");
  svg.setAttribute("aria-label", "Queries over time: when each was asked and answered");
  const add = (name, attrs, content) => {
    const e = document.createElementNS(NS, name);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
    if (content !== undefined) e.textContent = content;
    svg.append(e);
    return e;
  };
  add("line", { x1: 30, y1: 45, x2: W - 30, y2: 45, stroke: "#c9c4b8" });
  const color = (v) => (v === 1 || v === "left" || (typeof v === "number" && v > 0) ? "#2e7d4f" : v === -1 || v === "right" || (typeof v === "number" && v < 0) ? "#b3413b" : "#6b7280");
  const y = (v) => (typeof v === "number" ? 45 - 20 * v : v === "left" ? 25 : v === "right" ? 65 : 45);
  for (const a of answers) {
    const xa = X(Date.parse(a.asked_at));
    const xb = X(Date.parse(a.answered_at));
    add("line", { x1: xa, y1: y(a.value), x2: Math.max(xb, xa + 1), y2: y(a.value), stroke: color(a.value), "stroke-width": 3, opacity: 0.4 });
    const c = add("circle", { cx: xb, cy: y(a.value), r: 5, fill: color(a.value) });
    const title = document.createElementNS(NS, "title");
    title.textContent = `query ${a.query_id}: ${valueWords(a.value)} by ${a.trainer ?? a.who}, ${a.latency_ms} ms after it was asked`;
    c.append(title);
  }
  const pos = answers[0].kind === "preference" ? ["left", "right"] : ["good", "bad"];
  add("text", { x: 0, y: 28, class: "tick" }, pos[0]);
  add("text", { x: 0, y: 68, class: "tick" }, pos[1]);
  add("text", { x: 30, y: 86, class: "tick" }, "0 s");
  add("text", { x: W - 30, y: 86, class: "tick", "text-anchor": "end" }, `${((t1 - t0) / 1000).toFixed(1)} s`);
  box.replaceChildren(svg);
}

async function load() {
  let session;
  try {
    session = await getJson(`/api/sessions/${encodeURIComponent(sessionId)}`);
  } catch (e) {
    if (e instanceof ApiError && e.status === 401) {
      $("login").classList.remove("hidden");
      $("content").classList.add("hidden");
      if (getToken()) notify("The token was refused.", { kind: "error" });
      return;
    }
    $("title").textContent = "Review";
    notify(`This session cannot be shown: ${e.message}`, { kind: "error", timeoutMs: 0 });
    $("content").replaceChildren(text("p", `This session cannot be shown: ${e.message}`, "panel"));
    $("content").classList.remove("hidden");
    return;
  }
  $("login").classList.add("hidden");
  $("content").classList.remove("hidden");
  $("title").textContent = `Review · ${session.task} · ${session.method} · ${session.id}`;
  $("status").textContent = session.status;
  $("status").className = `pill ${session.status}`;
  const base = `/api/sessions/${encodeURIComponent(sessionId)}`;
  const [episodes, answers, trainers, agreement] = await Promise.all([
    getJson(`/api/sessions/${encodeURIComponent(sessionId)}/episodes`).catch((e) => {
      notify(`The episodes could not be loaded: ${e.message}`, { kind: "error" });
      return [];
    }),
    getJson(`/api/sessions/${encodeURIComponent(sessionId)}/answers`).catch((e) => {
      notify(`The answers could not be loaded: ${e.message}`, { kind: "error" });
      return [];
    }),
    getJson(`${base}/trainers`).catch((e) => {
      notify(`The trainers could not be loaded: ${e.message}`, { kind: "error" });
      return [];
    }),
    getJson(`${base}/agreement`).catch((e) => {
      notify(`The agreement could not be loaded: ${e.message}`, { kind: "error" });
      return null;
    }),
  ]);
  showTrainers(trainers, agreement);
  const dl = $("metrics");
  dl.replaceChildren();
  metric(dl, "Trainer", session.trainer);
  metric(dl, "Progress", `${session.progress.toLocaleString()} / ${session.budget.toLocaleString()} ${session.unit}`);
  metric(dl, "Answers", String(session.answers?.total ?? answers.length));
  metric(dl, "No feedback (NFC)", String(session.answers?.no_feedback ?? 0));
  metric(dl, "Trainer time (T)", session.trainer_seconds == null ? "–" : `${session.trainer_seconds.toFixed(1)} s`);
  const lat = answers.filter((a) => a.who === "trainer" || a.who === "trainers").map((a) => a.latency_ms).sort((a, b) => a - b);
  metric(dl, "Median latency", lat.length ? `${(lat[Math.floor(lat.length / 2)] / 1000).toFixed(2)} s` : "–");
  if (episodes.length) metric(dl, "Cumulative reward", episodes[episodes.length - 1].cumulative_return.toFixed(1));
  for (const [k, label] of Object.entries(SURVEY_WORDS)) {
    const v = session.survey?.[k];
    metric(dl, label, v == null ? "not answered" : `${v} / 5`);
  }

  linePlot($("plot-returns"), [{ points: episodes.map((e) => [e.episode, e.return]) }], { xLabel: "episode", yLabel: "return", height: 130, empty: session.unit === "queries" ? "preference sessions have no episodes" : "no finished episode" });
  const tbody = document.querySelector("#episodes tbody");
  tbody.replaceChildren(
    ...episodes.map((e) => {
      const tr = document.createElement("tr");
      tr.dataset.episode = String(e.episode);
      tr.append(text("td", String(e.episode), "num"), text("td", e.step.toLocaleString(), "num"), text("td", e.return.toFixed(1), "num"), text("td", String(e.length), "num"), text("td", e.outcome));
      const b = text("button", "Replay");
      b.type = "button";
      b.addEventListener("click", () => loadEpisode(e, tr));
      const td = document.createElement("td");
      td.append(b);
      tr.append(td);
      return tr;
    }),
  );
  $("episodes-empty").classList.toggle("hidden", episodes.length > 0);

  timeline(answers);
  const ab = document.querySelector("#answers tbody");
  ab.replaceChildren(
    ...answers.map((a) => {
      const tr = document.createElement("tr");
      const cls = a.value === 1 || a.value === "left" ? "value-good" : a.value === -1 || a.value === "right" ? "value-bad" : "";
      tr.append(text("td", String(a.query_id), "num"), text("td", a.kind), text("td", String(a.step), "num"), text("td", valueWords(a.value), cls), text("td", a.trainer ?? a.who), text("td", `${(a.latency_ms / 1000).toFixed(2)} s`, "num"), text("td", new Date(a.answered_at).toLocaleTimeString()));
      return tr;
    }),
  );
  $("answers-empty").classList.toggle("hidden", answers.length > 0);
  $("rerun-cmd").textContent = `rerun dualrep-${session.id}.rrd`;
}

function start() {
  $("login-form").addEventListener("submit", (ev) => {
    ev.preventDefault();
    setToken($("token").value.trim());
    load();
  });
  $("play").addEventListener("click", () => setPlaying(!replay.playing));
  $("back").addEventListener("click", () => stepBy(-1));
  $("fwd").addEventListener("click", () => stepBy(1));
  $("speed").addEventListener("change", () => {
    replay.speed = Number($("speed").value);
  });
  $("scrub").addEventListener("input", () => {
    setPlaying(false);
    replay.index = Number($("scrub").value);
    drawReplay();
  });
  $("download-rrd").addEventListener("click", async () => {
    try {
      await download(`/api/sessions/${encodeURIComponent(sessionId)}/recording.rrd`, `dualrep-${sessionId}.rrd`);
    } catch (e) {
      notify(`The recording could not be downloaded: ${e.message}`, { kind: "error" });
    }
  });
  document.addEventListener("keydown", (ev) => {
    const t = ev.target;
    if (t instanceof HTMLInputElement || t instanceof HTMLSelectElement || !replay.clip) return;
    if (ev.key === "k" || ev.key === "K") setPlaying(!replay.playing);
    else if (ev.key === "ArrowLeft") stepBy(-1);
    else if (ev.key === "ArrowRight") stepBy(1);
    else return;
    ev.preventDefault();
  });
  onResize([$("replay-stage")], drawReplay);
  requestAnimationFrame(tick);
  if (!sessionId) {
    notify("No session in the address: /review/{session}.", { kind: "error", timeoutMs: 0 });
    return;
  }
  if (!getToken()) {
    $("login").classList.remove("hidden");
    return;
  }
  load();
}

start();
