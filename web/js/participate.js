// A participant's page of a study (/study/{link}): who they are (their own link's
// ?participant=TOKEN, else the token this browser kept for the study, else a new participant
// joined from the link), then the step the server says they are at: consent, their sessions in
// their order, the next one to start, training (their place in the queue and the trainer page,
// which comes back here when the session ends), the survey after each condition, the end.
// Every failed request shows the server's message. `body[data-step]` names the step shown.

import { postJson, request } from "./api.js";
import { notify } from "./notify.js";

const $ = (id) => document.getElementById(id);
const POLL_MS = 1500;
const SECTIONS = ["consent", "ready", "training", "survey", "done"];

const link = decodeURIComponent(location.pathname.split("/").filter(Boolean)[1] || "");
const KEY = `dualrep.study.${link}`;
const base = `/api/study-links/${encodeURIComponent(link)}/participants`;

const page = { token: "", view: null, pollTimer: null, surveyFor: null };

// Participants' routes carry the token in the path: never send the researcher's.
const NO_TOKEN = { token: "" };

function tokenOf(url) {
  return new URL(url, location.origin).searchParams.get("participant") || "";
}

function own() {
  return `${base}/${encodeURIComponent(page.token)}`;
}

function setStep(name) {
  document.body.dataset.step = name;
}

function failed(what, e) {
  notify(`${what}: ${e.message}`, { kind: "error", key: what });
}

// ---- who this is ----------------------------------------------------------------------------

/** The participant's view: from their link, from this browser, or as a new participant. */
async function arrive() {
  const fromUrl = new URLSearchParams(location.search).get("participant");
  const kept = localStorage.getItem(KEY);
  for (const token of [fromUrl, kept]) {
    if (!token) continue;
    try {
      return await ownView(token);
    } catch (e) {
      // A token this browser kept that the server no longer knows: join anew. A link's own
      // token that fails is shown as it is.
      if (token === fromUrl || ![403, 404].includes(e.status)) throw e;
      localStorage.removeItem(KEY);
      notify(`Your earlier visit could not be found (${e.message}); you start afresh.`, { kind: "info" });
    }
  }
  const view = await postJson(base, undefined, NO_TOKEN);
  page.token = tokenOf(view.url);
  localStorage.setItem(KEY, page.token);
  history.replaceState(null, "", view.url);
  return view;
}

async function ownView(token) {
  page.token = token;
  const view = await (await request(own(), NO_TOKEN)).json();
  localStorage.setItem(KEY, token);
  history.replaceState(null, "", view.url);
  return view;
}

// ---- the steps ------------------------------------------------------------------------------

function nameAt(view, position) {
  return view.ordering[position] ?? "";
}

// What the participant sees: the condition's label, never the method's name.
function labelAt(view, position) {
  return view.labels?.[position] ?? `Session ${position + 1}`;
}

function sessionWords(view, position) {
  return `Session ${position + 1} of ${view.ordering.length}: ${labelAt(view, position)}`;
}

function showPlan(view) {
  const step = view.step;
  const current = step.position ?? (step.step === "done" ? view.ordering.length : -1);
  $("conditions").replaceChildren(
    ...view.ordering.map((name, i) => {
      const li = document.createElement("li");
      li.dataset.condition = name;
      li.dataset.position = String(i);
      const state = step.step === "consent" ? "todo" : i < current ? "done" : i === current ? "current" : "todo";
      li.className = state;
      const label = Object.assign(document.createElement("span"), { className: "name", textContent: labelAt(view, i) });
      const note = Object.assign(document.createElement("span"), {
        className: "note muted small",
        textContent: { done: "done", current: "now", todo: "" }[state],
      });
      li.append(label, note);
      if (state === "current") li.setAttribute("aria-current", "step");
      return li;
    }),
  );
  const mine = new URL(view.url, location.origin).href;
  $("own-link").href = mine;
  $("own-link").textContent = mine;
}

function showTraining(view) {
  const t = view.training;
  $("training-title").textContent = sessionWords(view, view.step.position);
  let words;
  if (!t) words = "Your session is starting…";
  else if (t.status === "queued") {
    words =
      t.queued_ahead > 0
        ? `Other people are training now: ${t.queued_ahead} session${t.queued_ahead === 1 ? "" : "s"} before yours. You can open your session already; it starts as soon as a place is free.`
        : "Other people are training now; yours is next. You can open your session already; it starts as soon as a place is free.";
  } else words = "Your session is running: open it and teach the robot. You come back here when it ends.";
  $("queue").textContent = words;
  $("queue").dataset.status = t?.status ?? "";
  if (t) {
    const next = encodeURIComponent(view.url);
    $("train-link").href = `${t.trainer_url}&next=${next}`;
  }
  $("train-link").classList.toggle("hidden", !t);
}

function scale(question) {
  const fs = document.createElement("fieldset");
  fs.dataset.question = question.id;
  fs.append(Object.assign(document.createElement("legend"), { textContent: question.text }));
  const row = document.createElement("div");
  row.className = "scale";
  row.append(Object.assign(document.createElement("span"), { className: "end", textContent: question.low }));
  for (let v = 1; v <= question.points; v += 1) {
    const label = document.createElement("label");
    const input = Object.assign(document.createElement("input"), { type: "radio", name: `q-${question.id}`, value: String(v), required: true });
    label.append(input, String(v));
    row.append(label);
  }
  row.append(Object.assign(document.createElement("span"), { className: "end", textContent: question.high }));
  fs.append(row);
  return fs;
}

function showSurvey(view) {
  const { position, session_id: sessionId, ended_early: endedEarly } = view.step;
  $("survey-title").textContent = `About ${sessionWords(view, position).replace(/^Session/, "session")}`;
  $("survey-form").dataset.condition = nameAt(view, position);
  $("ended-early").classList.toggle("hidden", !endedEarly);
  if (page.surveyFor === sessionId) return; // keep what is ticked
  page.surveyFor = sessionId;
  const submit = Object.assign(document.createElement("button"), { type: "submit", className: "primary", textContent: "Send answers" });
  $("survey-form").replaceChildren(...view.survey.map(scale), submit);
}

async function sendSurvey(ev) {
  ev.preventDefault();
  const form = ev.target;
  const data = new FormData(form);
  const answers = {};
  for (const q of page.view.survey) answers[q.id] = Number(data.get(`q-${q.id}`));
  const button = form.querySelector("button[type=submit]");
  button.disabled = true;
  try {
    render(await postJson(`${own()}/survey`, { condition: form.dataset.condition, answers }, NO_TOKEN));
    notify("Thank you, your answers are saved.", { kind: "ok" });
  } catch (e) {
    failed("Your answers could not be saved", e);
  } finally {
    button.disabled = false;
  }
}

function render(view) {
  page.view = view;
  const step = view.step.step;
  $("loading").classList.add("hidden");
  $("title").textContent = view.title;
  document.title = `${view.title} · dualrep`;
  $("who").textContent = `You: ${view.participant_id}`;
  $("who").classList.remove("hidden");
  document.body.dataset.participant = view.participant_id;
  $("consent-text").textContent = view.consent;
  for (const name of SECTIONS) $(name).classList.toggle("hidden", name !== step);
  $("plan").classList.remove("hidden");
  showPlan(view);
  if (step === "ready") $("ready-title").textContent = sessionWords(view, view.step.position);
  if (step === "training") showTraining(view);
  if (step === "survey") showSurvey(view);
  setStep(step);
  clearTimeout(page.pollTimer);
  if (step === "training") page.pollTimer = setTimeout(refresh, POLL_MS);
}

async function refresh() {
  try {
    render(await (await request(own(), NO_TOKEN)).json());
  } catch (e) {
    failed("Where you are could not be loaded", e);
    clearTimeout(page.pollTimer);
    page.pollTimer = setTimeout(refresh, POLL_MS);
  }
}

/** A button that posts to the participant's route `path` and shows the step that follows. */
function action(button, path, what) {
  button.addEventListener("click", async () => {
    button.disabled = true;
    try {
      render(await postJson(`${own()}/${path}`, undefined, NO_TOKEN));
    } catch (e) {
      failed(what, e);
      // Something moved elsewhere (another tab): show where things are.
      if (e.status === 409) await refresh();
    } finally {
      button.disabled = false;
    }
  });
}

async function start() {
  action($("agree"), "consent", "Your consent could not be saved");
  action($("start"), "start", "The session could not be started");
  $("survey-form").addEventListener("submit", sendSurvey);
  // Back from the trainer page through the browser's history: show where things are now.
  window.addEventListener("pageshow", (ev) => {
    if (ev.persisted && page.token) refresh();
  });
  if (!link) {
    $("loading").textContent = "This link is incomplete: it needs the study's link (/study/...).";
    notify("This study link is incomplete. Ask for the link again.", { kind: "error", timeoutMs: 0 });
    setStep("error");
    return;
  }
  try {
    render(await arrive());
  } catch (e) {
    $("loading").textContent = `This study could not be opened: ${e.message}`;
    notify(`This study could not be opened: ${e.message}`, { kind: "error", timeoutMs: 0 });
    setStep("error");
  }
}

start();
