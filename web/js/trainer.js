// The trainer page (/train/{session}?token=...): the robot live, the queries with their clips,
// answers by key or click, progress, undo, and the three questions at the end. On the session's
// shared link the page asks for a name: joining gives this person a link of their own (kept in
// this browser), so every answer is stored with who gave it; sessions that take several
// answers per query count only named trainers' answers. A study's session comes with
// `&next=/study/...` (the participant's own page): the page asks no name, and at the end it
// offers "Continue the study" there instead of its three questions (the study asks its own).

import { ClipLoop } from "./clip.js";
import { notify } from "./notify.js";
import { postJson } from "./api.js";
import { linePlot } from "./plot.js";
import { describeAction, drawScene } from "./render.js";
import { TrainerSocket, socketUrl } from "./socket.js";
import { buildSurvey } from "./survey.js";
import { buildStage, onResize } from "./stage.js";

const UNDO_WINDOW_MS = 6000;
const TASK_NAMES = { reaching: "Reaching", placing: "Placing", "lunar-lander": "Lunar Lander" };
const EVAL_KEYS = { ArrowUp: 1, " ": 0, ArrowDown: -1 };
const PREF_KEYS = { ArrowLeft: "left", ArrowRight: "right", ArrowDown: "equal", "=": "equal", " ": "skip" };
const VALUE_WORDS = { 1: "Good", 0: "No feedback", "-1": "Bad", left: "Left", right: "Right", equal: "About equal", skip: "Skipped" };

const $ = (id) => document.getElementById(id);

const sessionId = decodeURIComponent(location.pathname.split("/").filter(Boolean)[1] || "");
const NAMED_KEY = `dualrep.trainer.${sessionId}`;
// A trainer who named themself on this session before comes back under their own token.
let token = localStorage.getItem(NAMED_KEY) || new URLSearchParams(location.search).get("token") || "";

/** `?next=`: where a study continues, only a path on this server under /study/; else null. */
function studyNext() {
  const raw = new URLSearchParams(location.search).get("next");
  if (!raw || !raw.startsWith("/study/") || raw.includes("\\")) return null;
  let url;
  try {
    url = new URL(raw, location.origin);
  } catch {
    return null;
  }
  if (url.origin !== location.origin || !url.pathname.startsWith("/study/")) return null;
  return url.pathname + url.search + url.hash;
}
const NEXT = studyNext();

const page = {
  hello: null,
  geometry: null,
  liveViews: [],
  liveState: null,
  liveDirty: false,
  query: null, // the query on screen: {msg, sent, value}
  loop: null,
  acked: new Map(), // id -> value, answers stored this visit
  history: [], // [{id, value, at, el}]
  lastAnswer: null,
  firstQueryAt: null,
  lastAnswerAt: null,
  noFeedback: 0,
  expiresAt: 0,
  ended: false,
  socket: null,
};

function setState(name) {
  document.body.dataset.state = name;
}

function setPill(el, text, cls) {
  el.textContent = text;
  el.className = `pill ${cls}`;
}

// ---- the live view --------------------------------------------------------------------------

function setGeometry(geometry) {
  if (!geometry) return;
  const same = page.geometry && JSON.stringify(page.geometry) === JSON.stringify(geometry);
  page.geometry = geometry;
  if (!same || page.liveViews.length === 0) page.liveViews = buildStage($("live"), geometry);
  page.liveDirty = true;
}

function drawLive() {
  if (page.liveDirty && page.geometry && !$("live").classList.contains("hidden")) {
    for (const { canvas, view } of page.liveViews) drawScene(canvas, page.geometry, page.liveState, view);
    page.liveDirty = false;
  }
  requestAnimationFrame(drawLive);
}

// ---- queries --------------------------------------------------------------------------------

function chips(ul, labels) {
  ul.replaceChildren(
    ...(labels.length ? labels : ["—"]).map((l) => {
      const li = document.createElement("li");
      li.textContent = l;
      return li;
    }),
  );
}

function clearQuery() {
  page.loop?.stop();
  page.loop = null;
  page.query = null;
  for (const id of ["evaluative", "preference", "answers-eval", "answers-pref"]) $(id).classList.add("hidden");
  $("live").classList.remove("hidden");
  $("evaluative").removeAttribute("data-query-id");
  $("preference").removeAttribute("data-query-id");
  $("expires").textContent = "";
  page.liveDirty = true;
  if (!page.ended) {
    $("prompt").textContent = "Watching the robot. It will ask you when it needs you.";
    setState("watching");
  }
}

function showQuery(msg) {
  if (page.query && page.query.msg.id === msg.id) return; // the same query again (rejoin)
  if (page.acked.has(msg.id)) return; // already answered on this page
  clearQuery();
  page.query = { msg, sent: false, value: null };
  page.firstQueryAt ??= Date.now();
  page.expiresAt = Date.now() + (msg.expires_in_ms ?? 0);
  const fps = Math.min(30, page.hello?.pace_hz ?? 20);
  $("live").classList.add("hidden");
  if (msg.kind === "evaluative") {
    const panes = [{ clip: msg.clip, canvases: buildStage($("eval-stage"), msg.clip.geometry), action: msg.action }];
    page.loop = new ClipLoop(panes, { fps });
    $("action-words").textContent = `The robot ${describeAction(msg.clip.geometry.task, msg.action)}.`;
    chips($("holding"), msg.holding ?? []);
    $("evaluative").dataset.queryId = String(msg.id);
    $("evaluative").classList.remove("hidden");
    $("answers-eval").classList.remove("hidden");
    $("prompt").textContent = "Was that good? Watch the clip: the arrow is what the robot did.";
  } else {
    const panes = [
      { clip: msg.left, canvases: buildStage($("left-stage"), msg.left.geometry, { maxHeight: msg.left.geometry.task === "placing" ? "27vh" : "50vh" }) },
      { clip: msg.right, canvases: buildStage($("right-stage"), msg.right.geometry, { maxHeight: msg.right.geometry.task === "placing" ? "27vh" : "50vh" }) },
    ];
    page.loop = new ClipLoop(panes, { fps });
    chips($("left-holding"), msg.left_holding ?? []);
    chips($("right-holding"), msg.right_holding ?? []);
    const differ = $("differ");
    if (msg.predicate) {
      differ.replaceChildren("They differ in: ", Object.assign(document.createElement("strong"), { textContent: msg.predicate.label }));
    } else {
      differ.textContent = "Compare the two clips.";
    }
    $("preference").dataset.queryId = String(msg.id);
    $("preference").classList.remove("hidden");
    $("answers-pref").classList.remove("hidden");
    $("prompt").textContent = "Which one is better?";
  }
  for (const b of document.querySelectorAll(".answer")) {
    b.disabled = false;
    b.classList.remove("chosen");
  }
  page.loop.play();
  setState("query");
}

function answer(value) {
  const q = page.query;
  if (!q || q.sent || page.ended) return;
  q.sent = true;
  q.value = value;
  for (const b of document.querySelectorAll(".answer")) {
    b.disabled = true;
    b.classList.toggle("chosen", b.dataset.value === String(value));
  }
  page.socket.send({ type: "answer", id: q.msg.id, value });
  $("expires").textContent = page.socket.connected ? "Saving…" : "Saving as soon as the connection is back…";
  setState("saving");
}

/** Sends query `q`'s answer again after `ms`, unless it was settled meanwhile. */
function resendLater(q, ms) {
  setTimeout(() => {
    if (page.query === q && q.sent && !page.ended) page.socket.send({ type: "answer", id: q.msg.id, value: q.value });
  }, ms ?? 250);
}

function reenable() {
  if (!page.query) return;
  page.query.sent = false;
  for (const b of document.querySelectorAll(".answer")) b.disabled = false;
  setState("query");
}

function recordAnswer(id, value) {
  page.acked.set(id, value);
  page.lastAnswerAt = Date.now();
  if (value === 0 || value === "skip") page.noFeedback += 1;
  const li = document.createElement("li");
  li.textContent = `${VALUE_WORDS[String(value)] ?? value}`;
  li.dataset.queryId = String(id);
  $("history").prepend(li);
  page.history.unshift({ id, value, el: li });
  page.lastAnswer = { id, value, at: Date.now() };
  // Several trainers' answers combine and stand: no undo there.
  const combined = (page.hello?.answers_per_query ?? 1) > 1;
  notify(combined ? `Saved: ${VALUE_WORDS[String(value)] ?? value}. Waiting for the other trainers.` : `Saved: ${VALUE_WORDS[String(value)] ?? value}.`, {
    kind: "ok",
    timeoutMs: UNDO_WINDOW_MS,
    key: "answer",
    action: combined ? undefined : { label: "Undo (U)", run: undo },
  });
}

function undo() {
  const last = page.lastAnswer;
  if (!last || Date.now() - last.at > UNDO_WINDOW_MS || page.ended) return;
  page.socket.send({ type: "undo", id: last.id });
  page.lastAnswer = null;
}

function undone(id) {
  const value = page.acked.get(id);
  page.acked.delete(id);
  if (value === 0 || value === "skip") page.noFeedback -= 1;
  const h = page.history.find((x) => x.id === id);
  if (h) {
    h.el.classList.add("undone");
    h.el.textContent += " (undone)";
  }
  notify("Undone. The question is back: answer it again.", { kind: "info", key: "answer" });
}

// ---- progress -------------------------------------------------------------------------------

function showProgress(p) {
  $("answered").textContent = String(p.answered ?? 0);
  const left = Math.max(0, (p.budget ?? 0) - (p.progress ?? 0));
  $("remaining").textContent = `${left.toLocaleString()}`;
  $("progress-words").textContent = `${(p.progress ?? 0).toLocaleString()} of ${(p.budget ?? 0).toLocaleString()} ${p.unit ?? ""} done; ${left.toLocaleString()} ${p.unit ?? ""} remaining.`;
  $("feedback").textContent = p.unit === "steps" ? `${((p.feedback_fraction ?? 0) * 100).toFixed(1)}%` : "–";
  $("progressbar").style.width = `${p.budget ? Math.min(100, (100 * p.progress) / p.budget) : 0}%`;
  const returns = p.recent_returns ?? [];
  linePlot($("returns"), [{ points: returns.map((r, i) => [i + 1, r]) }], {
    width: 280,
    height: 120,
    xLabel: "recent episodes",
    empty: "no finished episode yet",
  });
}

// ---- the end and the three questions --------------------------------------------------------

function showEnd(msg) {
  page.ended = true;
  clearQuery();
  setPill($("status"), msg.status, msg.status);
  const words = { finished: "The session is finished.", stopped: "The session was stopped.", failed: "The session failed.", interrupted: "The server is restarting; this page will need reloading once it is back." };
  $("prompt").textContent = words[msg.status] ?? `The session ended (${msg.status}).`;
  if (msg.reason) $("prompt").textContent += ` ${msg.reason}`;
  setState("ended");
  $("live").classList.add("hidden");
  if (NEXT) {
    // A study's session: the study's page asks about it.
    $("continue").href = NEXT;
    $("continue-box").classList.remove("hidden");
    $("continue").focus();
  } else if (page.hello && page.acked.size + page.history.length > 0) {
    const seconds = page.firstQueryAt && page.lastAnswerAt ? Math.round((page.lastAnswerAt - page.firstQueryAt) / 1000) : 0;
    $("summary").textContent = `You answered ${page.acked.size} question${page.acked.size === 1 ? "" : "s"} over ${seconds} s on this page, ${page.noFeedback} of them without feedback. Three quick questions, 1 to 5:`;
    $("survey").classList.remove("hidden");
  } else if (msg.status === "finished") {
    $("summary").textContent = "Three quick questions, 1 to 5:";
    $("survey").classList.remove("hidden");
  }
}

// ---- messages -------------------------------------------------------------------------------

function onMessage(msg) {
  switch (msg.type) {
    case "hello":
      page.hello = msg;
      showWho(msg);
      {
        // A remote env's own task is called by its env's id, once the session has one.
        const name = msg.task === "remote" && msg.geometry?.env ? msg.geometry.env : TASK_NAMES[msg.task] ?? msg.task;
        // A study's participant is not told the method, so that its name cannot sway them.
        $("title").textContent = NEXT ? name : `${name} · ${msg.method.toUpperCase()}`;
        document.title = `${name} · Teach the robot`;
      }
      setPill($("status"), msg.status, msg.status);
      setGeometry(msg.geometry);
      if (!page.query && !page.ended) {
        $("prompt").textContent = msg.geometry ? "Watching the robot. It will ask you when it needs you." : "The session is about to start…";
        setState("watching");
      }
      break;
    case "frame":
      if (msg.geometry) setGeometry(msg.geometry);
      page.liveState = msg.state;
      page.liveDirty = true;
      break;
    case "query":
      showQuery(msg);
      break;
    case "ack":
      if (page.query && page.query.msg.id === msg.id) clearQuery();
      if (!page.acked.has(msg.id)) recordAnswer(msg.id, msg.value);
      break;
    case "undone":
      undone(msg.id);
      break;
    case "withdrawn":
      if (page.query && page.query.msg.id === msg.id) {
        clearQuery();
        const why = { answered: "Another trainer answered that one first.", expired: "That question timed out and counted as no feedback.", ended: "The session ended." };
        notify(why[msg.reason] ?? "That question was withdrawn.", { kind: "info" });
      }
      break;
    case "progress":
      showProgress(msg);
      break;
    case "error":
      onError(msg);
      break;
    case "ended":
      showEnd(msg);
      break;
    default:
      break;
  }
}

function onError(msg) {
  const mine = page.query && msg.id === page.query.msg.id;
  switch (msg.code) {
    case "undo_unavailable":
      notify(`Could not undo: ${msg.message}`, { kind: "info", key: "answer" });
      return;
    case "identity_required":
      if (mine) reenable();
      $("name-form").classList.remove("hidden");
      $("name").focus();
      notify(msg.message, { kind: "info" });
      return;
    case "rate_limited":
      // The server took nothing and said when to send again: the person has answered, so the
      // page sends the same answer then instead of asking them twice.
      if (mine && page.query.sent) {
        resendLater(page.query, msg.retry_after_ms);
        return;
      }
      notify(`${msg.message} Please try again.`, { kind: "error" });
      return;
    case "store_failed":
      if (mine) reenable();
      notify(`${msg.message} Please answer again.`, { kind: "error" });
      return;
    case "expired":
    case "unknown_query":
    case "session_ended":
    case "already_answered":
      if (mine) clearQuery();
      notify(msg.message, { kind: "info" });
      return;
    default:
      if (mine) reenable();
      notify(msg.message || msg.code, { kind: "error" });
  }
}

function onSocketState(state, info) {
  const pill = $("connection");
  $("retry").classList.toggle("hidden", state !== "reconnecting");
  if (state === "connected") setPill(pill, "connected", "connected");
  else if (state === "connecting") setPill(pill, "connecting…", "reconnecting");
  else if (state === "reconnecting") {
    setPill(pill, info.inMs ? `reconnecting in ${Math.ceil(info.inMs / 1000)} s` : "reconnecting…", "reconnecting");
    document.body.dataset.connection = "reconnecting";
  } else if (state === "closed") setPill(pill, page.ended ? "done" : "closed", "offline");
  if (state === "connected") document.body.dataset.connection = "connected";
  if (state === "closed" && !page.ended) {
    $("prompt").textContent = "The connection was refused. Check the link you were given.";
  }
}

// ---- who is answering -----------------------------------------------------------------------

function showWho(hello) {
  const named = hello.trainer;
  $("who").classList.toggle("hidden", !named);
  if (named) {
    $("who").textContent = `You: ${named.name}`;
    document.body.dataset.trainer = named.name;
  }
  const ended = ["finished", "failed", "stopped", "interrupted"].includes(hello.status);
  // A study's participants stay pseudonymous: no name asked.
  const ask = !named && !ended && !NEXT;
  $("name-form").classList.toggle("hidden", !ask);
  $("name-why").textContent =
    hello.answers_per_query > 1
      ? `This session asks ${hello.answers_per_query} people each question: give your name to answer.`
      : "Give your name so that your answers are yours (or just answer).";
}

async function joinWithName(ev) {
  ev.preventDefault();
  const name = $("name").value.trim();
  if (!name) return;
  $("join").disabled = true;
  try {
    const me = await postJson(`/api/sessions/${encodeURIComponent(sessionId)}/join`, { name }, { token });
    localStorage.setItem(NAMED_KEY, me.token);
    history.replaceState(null, "", me.trainer_url);
    token = me.token;
    // Connect again as this trainer: hello names them, and the open question follows.
    const old = page.socket;
    old.onState = () => {};
    old.onMessage = () => {};
    old.close();
    page.socket = new TrainerSocket(socketUrl(sessionId, token), { onMessage, onState: onSocketState });
    page.socket.connect();
    notify(`Welcome, ${me.name}.`, { kind: "ok" });
  } catch (e) {
    notify(`Could not join: ${e.message}`, { kind: "error" });
  } finally {
    $("join").disabled = false;
  }
}

// ---- keys -----------------------------------------------------------------------------------

function onKey(ev) {
  if (ev.altKey || ev.ctrlKey || ev.metaKey) return;
  const t = ev.target;
  if (t instanceof HTMLInputElement || t instanceof HTMLTextAreaElement || t instanceof HTMLSelectElement) return;
  if (ev.key === "u" || ev.key === "U") {
    undo();
    return;
  }
  if (!page.query) return;
  const map = page.query.msg.kind === "evaluative" ? EVAL_KEYS : PREF_KEYS;
  if (Object.hasOwn(map, ev.key)) {
    ev.preventDefault();
    answer(map[ev.key]);
  }
}

function tickExpiry() {
  if (page.query && !page.query.sent && page.expiresAt) {
    const s = Math.max(0, Math.ceil((page.expiresAt - Date.now()) / 1000));
    const then = page.query.msg.kind === "evaluative" ? "no feedback" : "skipped";
    $("expires").textContent = `${s} s left, then it counts as ${then}.`;
  }
}

function start() {
  buildSurvey({ sessionId, token: () => token, onSaved: () => setState("survey-saved") });
  $("name-form").addEventListener("submit", joinWithName);
  for (const b of document.querySelectorAll(".answer")) {
    b.addEventListener("click", () => {
      const v = b.dataset.value;
      answer(/^-?\d+$/.test(v) ? Number(v) : v);
    });
  }
  document.addEventListener("keydown", onKey);
  setInterval(tickExpiry, 250);
  onResize([$("live"), $("eval-stage"), $("left-stage")], () => {
    page.liveDirty = true;
    page.loop?.redraw();
  });
  requestAnimationFrame(drawLive);
  showProgress({});
  if (!sessionId || !token) {
    $("prompt").textContent = "This link is incomplete: it needs a session and a token (/train/{session}?token=...).";
    notify("This trainer link is missing its session or token. Ask for a new link.", { kind: "error", timeoutMs: 0 });
    setState("error");
    return;
  }
  page.socket = new TrainerSocket(socketUrl(sessionId, token), { onMessage, onState: onSocketState });
  $("retry").addEventListener("click", () => page.socket.retryNow());
  page.socket.connect();
}

start();
