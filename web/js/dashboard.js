// The dashboard (/): researcher token, launch form built from GET /api/tasks, the sessions
// table with live status, live plots of the selected session, and its named trainers (invite
// one: a link of their own); the studies, each with its participant link and results page.

import { ApiError, download, getJson, getToken, postJson, setToken } from "./api.js";
import { notify, notifyError } from "./notify.js";
import { linePlot } from "./plot.js";

const $ = (id) => document.getElementById(id);
const POLL_MS = 2000;
const ACTIVE = new Set(["queued", "running", "waiting"]);

const state = {
  tasks: null,
  sessions: [],
  selected: null,
  pollTimer: null,
};

// ---- sign in --------------------------------------------------------------------------------

function showLogin(message = "") {
  $("login").classList.remove("hidden");
  $("app").classList.add("hidden");
  $("signout").classList.add("hidden");
  $("signed").textContent = "";
  $("login-error").textContent = message;
  $("token").focus();
  clearTimeout(state.pollTimer);
}

async function signIn() {
  try {
    state.tasks ??= await getJson("/api/tasks");
    await getJson("/api/sessions");
  } catch (e) {
    if (e instanceof ApiError && e.status === 401) {
      showLogin(getToken() ? "That token was refused." : "");
      return;
    }
    notifyError(e, "The server did not answer");
    showLogin(`The server did not answer: ${e.message}`);
    return;
  }
  $("login").classList.add("hidden");
  $("app").classList.remove("hidden");
  $("signout").classList.remove("hidden");
  $("signed").textContent = "Signed in";
  buildForm();
  poll();
}

// ---- the launch form ------------------------------------------------------------------------

function isPreference(method) {
  return (state.tasks?.methods?.preference ?? []).includes(method);
}

function option(value, text = value) {
  return Object.assign(document.createElement("option"), { value, textContent: text });
}

function buildForm() {
  if ($("task").options.length) return;
  const t = state.tasks;
  for (const task of t.tasks) $("task").append(option(task.id));
  // A remote env's own task (needs an env URL): its predicates come from the env.
  $("task").append(option("remote", "remote (the env's own task)"));
  const ev = $("method");
  const g1 = Object.assign(document.createElement("optgroup"), { label: "evaluative (steps)" });
  for (const m of t.methods.evaluative.filter((m) => !m.includes("<"))) g1.append(option(m));
  const g2 = Object.assign(document.createElement("optgroup"), { label: "preference (queries)" });
  for (const m of t.methods.preference) g2.append(option(m));
  ev.append(g1, g2);
  $("task").addEventListener("change", fillDefaults);
  $("method").addEventListener("change", fillDefaults);
  $("launch-form").addEventListener("submit", launch);
  fillDefaults();
}

/** A remote env's own task: nothing known before the env is reached but the budgets. */
const REMOTE_TASK = { id: "remote", defaults: { steps: 100000, queries: 40 }, settings: { evaluative: {}, preference: {} } };

function currentTask() {
  return state.tasks.tasks.find((t) => t.id === $("task").value) ?? REMOTE_TASK;
}

function fillDefaults() {
  const task = currentTask();
  const pref = isPreference($("method").value);
  $("budget-label").textContent = pref ? "Queries" : "Steps";
  $("budget").placeholder = String(pref ? task.defaults.queries : task.defaults.steps);
  // The server's one list of settings, at their defaults for this task and method family.
  const settings = task.settings[pref ? "preference" : "evaluative"];
  $("pace_hz").placeholder = String(settings.pace_hz ?? 20);
  $("answer_timeout_s").placeholder = String(settings.answer_timeout_s ?? 60);
  const box = $("params");
  box.replaceChildren();
  for (const [k, v] of Object.entries(settings)) {
    if (["pace_hz", "answer_timeout_s"].includes(k)) continue;
    const label = document.createElement("label");
    label.textContent = k;
    const input = Object.assign(document.createElement("input"), { name: `param:${k}`, placeholder: JSON.stringify(v) });
    input.dataset.param = k;
    label.append(input);
    box.append(label);
  }
}

function parseValue(text) {
  try {
    return JSON.parse(text);
  } catch {
    return text;
  }
}

async function launch(ev) {
  ev.preventDefault();
  const method = $("method").value;
  const body = { task: $("task").value, method, trainer: $("trainer").value, seed: Number($("seed").value || 0), params: {} };
  const envUrl = $("env_url").value.trim();
  if (envUrl) body.env = { url: envUrl };
  if (body.task === "remote") {
    if (!envUrl) {
      notify("The task 'remote' is an env's own task: give its env URL.", { kind: "error" });
      return;
    }
    delete body.task;
  }
  if ($("budget").value) body[isPreference(method) ? "queries" : "steps"] = Number($("budget").value);
  for (const k of ["pace_hz", "answer_timeout_s"]) if ($(k).value) body.params[k] = Number($(k).value);
  for (const input of $("params").querySelectorAll("input")) {
    if (input.value.trim()) body.params[input.dataset.param] = parseValue(input.value.trim());
  }
  const extra = $("extra").value.trim();
  if (extra) {
    let more;
    try {
      more = JSON.parse(extra);
    } catch (e) {
      notify(`"More parameters" is not JSON: ${e.message}`, { kind: "error" });
      return;
    }
    Object.assign(body.params, more);
  }
  $("launch").disabled = true;
  $("launch-result").textContent = "Launching…";
  try {
    const created = await postJson("/api/sessions", body);
    const link = new URL(created.trainer_url, location.origin).href;
    $("launch-result").replaceChildren(`Session ${created.id} is ${created.status}. `);
    if (body.trainer === "human") {
      const a = Object.assign(document.createElement("a"), { href: link, target: "_blank", textContent: "Open the trainer page", id: "trainer-link" });
      $("launch-result").append(a);
    }
    state.selected = created.id;
    await refresh();
  } catch (e) {
    $("launch-result").textContent = `Not launched: ${e.message}`;
    notifyError(e, "Not launched");
  } finally {
    $("launch").disabled = false;
  }
}

// ---- the sessions table ---------------------------------------------------------------------

function fmtPct(x) {
  return x === undefined || x === null ? "–" : `${(x * 100).toFixed(1)}%`;
}

function actionButton(text, run, title = text) {
  const b = Object.assign(document.createElement("button"), { type: "button", textContent: text, title });
  b.addEventListener("click", async (ev) => {
    ev.stopPropagation();
    b.disabled = true;
    try {
      await run();
    } catch (e) {
      notifyError(e, `${text} failed`);
    } finally {
      b.disabled = false;
    }
  });
  return b;
}

function row(s) {
  const tr = document.createElement("tr");
  tr.dataset.id = s.id;
  tr.classList.toggle("selected", s.id === state.selected);
  const td = (content, cls) => {
    const c = document.createElement("td");
    if (cls) c.className = cls;
    if (content instanceof Node) c.append(content);
    else c.textContent = content;
    tr.append(c);
    return c;
  };
  td(Object.assign(document.createElement("code"), { textContent: s.id }));
  td(s.env ? `${s.task} @ ${s.env.url}` : s.task);
  td(s.method);
  td(s.trainer);
  td(Object.assign(document.createElement("span"), { className: `pill ${s.status}`, textContent: s.status, title: s.reason ?? "" }));
  const bar = document.createElement("div");
  bar.className = "progressbar";
  bar.title = `${s.progress} of ${s.budget} ${s.unit}`;
  bar.append(Object.assign(document.createElement("span"), { style: `width:${s.budget ? Math.min(100, (100 * s.progress) / s.budget) : 0}%` }));
  td(bar);
  td(String(s.answers?.total ?? 0), "num");
  td(String(s.answers?.no_feedback ?? 0), "num");
  td(s.unit === "steps" ? fmtPct(s.latest?.feedback_fraction) : "–", "num");
  const actions = document.createElement("div");
  actions.className = "actions";
  if (ACTIVE.has(s.status)) actions.append(actionButton("Stop", () => postJson(`/api/sessions/${s.id}/stop`).then(refresh)));
  if (["stopped", "interrupted", "failed"].includes(s.status)) actions.append(actionButton("Resume", () => postJson(`/api/sessions/${s.id}/resume`).then(refresh)));
  actions.append(actionButton("Export", () => download(`/api/sessions/${s.id}/export?format=jsonl`, `dualrep-${s.id}.jsonl`), "Download answers, episodes and metrics (JSONL)"));
  actions.append(actionButton("CSV", () => download(`/api/sessions/${s.id}/export?format=csv`, `dualrep-${s.id}.csv`), "Download the answers as CSV"));
  if (s.trainer === "human") {
    actions.append(
      actionButton("Copy link", async () => {
        const link = new URL(s.trainer_url, location.origin).href;
        try {
          await navigator.clipboard.writeText(link);
          notify("Trainer link copied.", { kind: "ok" });
        } catch {
          notify(`Copy this trainer link: ${link}`, { kind: "info", timeoutMs: 0 });
        }
      }, "Copy the trainer link"),
    );
    actions.append(Object.assign(document.createElement("a"), { className: "button", href: s.trainer_url, target: "_blank", textContent: "Train" }));
  }
  actions.append(Object.assign(document.createElement("a"), { className: "button", href: `/review/${s.id}`, textContent: "Review" }));
  td(actions);
  tr.addEventListener("click", () => {
    state.selected = s.id;
    render();
    showDetail();
  });
  return tr;
}

function render() {
  const tbody = document.querySelector("#sessions tbody");
  tbody.replaceChildren(...state.sessions.map(row));
  $("empty").classList.toggle("hidden", state.sessions.length > 0);
  $("updated").textContent = `updated ${new Date().toLocaleTimeString()}`;
}

async function refresh() {
  try {
    state.sessions = await getJson("/api/sessions");
  } catch (e) {
    if (e instanceof ApiError && e.status === 401) {
      showLogin("The token was refused.");
      return;
    }
    notify(`The sessions could not be loaded: ${e.message}`, { kind: "error", key: "poll" });
    return;
  }
  render();
  await Promise.all([showDetail(), showStudies()]);
}

// ---- studies --------------------------------------------------------------------------------

async function showStudies() {
  let studies;
  try {
    studies = await getJson("/api/studies");
  } catch (e) {
    notify(`The studies could not be loaded: ${e.message}`, { kind: "error", key: "studies" });
    return;
  }
  $("studies").replaceChildren(
    ...studies.map((s) => {
      const li = document.createElement("li");
      li.dataset.study = s.id;
      const link = new URL(s.link, location.origin).href;
      li.append(
        Object.assign(document.createElement("a"), { href: `/study.html?id=${encodeURIComponent(s.id)}`, textContent: s.title, className: "study-results" }),
        Object.assign(document.createElement("span"), { className: "muted small", textContent: `${s.participants} participant${s.participants === 1 ? "" : "s"}` }),
        Object.assign(document.createElement("a"), { href: link, textContent: link, className: "study-link small", title: "The link to send to every participant" }),
      );
      return li;
    }),
  );
  $("studies-empty").classList.toggle("hidden", studies.length > 0);
}

// The paper's Figure 4 design on Reaching, as a starting point a researcher edits.
const EXAMPLE_STUDY = {
  title: "Teaching a robot arm",
  conditions: [
    { name: "dref", task: "reaching", method: "dref" },
    { name: "ef-50", task: "reaching", method: "ef-50" },
    { name: "sac", task: "reaching", method: "sac" },
  ],
  budget: { steps: 6000 },
};

async function createStudy(ev) {
  ev.preventDefault();
  let spec;
  try {
    spec = JSON.parse($("study-spec").value);
  } catch (e) {
    notify(`The study is not valid JSON: ${e.message}`, { kind: "error" });
    return;
  }
  $("create-study").disabled = true;
  try {
    const study = await postJson("/api/studies", spec);
    const link = new URL(study.link, location.origin).href;
    notify(`Study created. Send this link to every participant: ${link}`, { kind: "ok", timeoutMs: 0 });
    $("new-study").open = false;
    await showStudies();
  } catch (e) {
    notify(`The study was not created: ${e.message}`, { kind: "error", timeoutMs: 0 });
  } finally {
    $("create-study").disabled = false;
  }
}

function setUpStudyForm() {
  $("study-spec").value = JSON.stringify(EXAMPLE_STUDY, null, 2);
  $("study-form").addEventListener("submit", createStudy);
}

function poll() {
  clearTimeout(state.pollTimer);
  refresh().finally(() => {
    state.pollTimer = setTimeout(poll, POLL_MS);
  });
}

// ---- the selected session's plots -----------------------------------------------------------

async function showDetail() {
  const s = state.sessions.find((x) => x.id === state.selected);
  if (!s) {
    $("detail").classList.add("hidden");
    return;
  }
  $("detail").classList.remove("hidden");
  $("detail-title").textContent = `${s.task} · ${s.method} · seed ${s.seed}`;
  $("detail-review").href = `/review/${s.id}`;
  const pref = s.unit === "queries";
  $("fig-alignment").classList.toggle("hidden", !pref);
  const metrics = [`${s.progress.toLocaleString()} of ${s.budget.toLocaleString()} ${s.unit}`, `${s.answers?.total ?? 0} answers (${s.answers?.by_trainer ?? 0} by the trainer, ${s.answers?.timeouts ?? 0} timed out)`, `no feedback: ${s.answers?.no_feedback ?? 0}`];
  if (s.trainer_seconds != null) metrics.push(`trainer time: ${s.trainer_seconds.toFixed(0)} s`);
  const pacing = s.latest?.pacing;
  if (pacing && s.method !== "sac") {
    // The rule's pacing as a person feels it (docs/dref.md).
    metrics.push(`longest flood: ${pacing.longest_flood} queries in a row`);
    metrics.push(`frozen after ${pacing.frozen_episodes} of ${pacing.episodes} episodes`);
    metrics.push(`last query ${pacing.steps_since_query} steps ago`);
  }
  $("detail-metrics").textContent = metrics.join(" · ");
  let episodes = [];
  try {
    episodes = await getJson(`/api/sessions/${s.id}/episodes`);
  } catch (e) {
    notify(`The episodes could not be loaded: ${e.message}`, { kind: "error", key: "episodes" });
  }
  const last = episodes[episodes.length - 1];
  const fb = last ? ` (feedback ${fmtPct(last.feedback_fraction)})` : "";
  linePlot($("plot-reward"), [{ label: `${s.method}${fb}`, points: episodes.map((e) => [e.step, e.cumulative_return]) }], { xLabel: "steps", height: 160, empty: pref ? "preference sessions have no episodes" : "no finished episode yet" });
  linePlot($("plot-returns"), [{ points: episodes.map((e) => [e.episode, e.return]) }], { xLabel: "episode", height: 160, empty: pref ? "preference sessions have no episodes" : "no finished episode yet" });
  showTrainerLinks(s);
  if (pref) {
    let curve = [];
    try {
      curve = await getJson(`/api/sessions/${s.id}/alignment`);
    } catch (e) {
      notify(`The alignment could not be loaded: ${e.message}`, { kind: "error", key: "alignment" });
    }
    const series = [
      { label: "alignment", points: curve.map((p) => [p.queries, p.alignment]) },
      { label: "of the mean", points: curve.map((p) => [p.queries, p.alignment_of_mean]) },
    ];
    linePlot($("plot-alignment"), curve.length ? series : [], { xLabel: "queries", yMin: -1, yMax: 1, height: 160, empty: "alignment is reported for synthetic trainers" });
  }
}

// ---- named trainers -------------------------------------------------------------------------

async function showTrainerLinks(s) {
  const human = s.trainer === "human";
  $("invite-box").classList.toggle("hidden", !human);
  if (!human) return;
  let trainers = [];
  try {
    trainers = await getJson(`/api/sessions/${s.id}/trainers`);
  } catch (e) {
    notify(`The trainers could not be loaded: ${e.message}`, { kind: "error", key: "trainers" });
  }
  const list = $("trainer-links");
  list.replaceChildren(
    ...trainers.map((t) => {
      const li = document.createElement("li");
      li.dataset.trainer = t.name ?? "";
      const who = Object.assign(document.createElement("strong"), { textContent: t.name ?? "anonymous" });
      li.append(who, `${t.answers} answers`);
      if (t.trainer_url) {
        const link = new URL(t.trainer_url, location.origin).href;
        li.append(Object.assign(document.createElement("a"), { href: link, target: "_blank", textContent: "their link", className: "trainer-link" }));
      }
      return li;
    }),
  );
}

async function invite(ev) {
  ev.preventDefault();
  const s = state.sessions.find((x) => x.id === state.selected);
  const name = $("invite-name").value.trim();
  if (!s || !name) return;
  try {
    const t = await postJson(`/api/sessions/${s.id}/trainers`, { name });
    $("invite-name").value = "";
    notify(`${t.name} is invited: send them their link.`, { kind: "ok" });
    await showTrainerLinks(s);
  } catch (e) {
    notifyError(e, "Not invited");
  }
}

// ---- start ----------------------------------------------------------------------------------

$("invite-form").addEventListener("submit", invite);
setUpStudyForm();

$("login-form").addEventListener("submit", (ev) => {
  ev.preventDefault();
  setToken($("token").value.trim());
  signIn();
});
$("signout").addEventListener("click", () => {
  setToken("");
  showLogin();
});
if (getToken()) signIn();
else showLogin();
