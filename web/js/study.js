// A study's results for the researcher (/study.html?id=STUDY): per condition n, sessions that
// ended early, cumulative reward, feedback %, T, NFC and the survey's medians; the cumulative
// reward curves (mean ± s.e.); the survey's distributions; the within-subject tests of every
// measure (Friedman, pairwise Wilcoxon with Holm's correction, effect sizes, cautions); the
// participants and where they are; the tidy table as CSV or Parquet. Polled every 5 s.

import { ApiError, download, getJson, getToken, setToken } from "./api.js";
import { notify } from "./notify.js";
import { linePlot } from "./plot.js";

const $ = (id) => document.getElementById(id);
const POLL_MS = 5000;
const SVG = "http://www.w3.org/2000/svg";
const studyId = new URLSearchParams(location.search).get("id") || "";
const api = `/api/studies/${encodeURIComponent(studyId)}`;
let pollTimer = null;

function text(tag, content, cls) {
  const e = document.createElement(tag);
  e.textContent = content;
  if (cls) e.className = cls;
  return e;
}

function svgEl(name, attrs = {}, content) {
  const e = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
  if (content !== undefined) e.textContent = content;
  return e;
}

const finite = (x) => typeof x === "number" && Number.isFinite(x);

function num(x, digits = 1) {
  return finite(x) ? x.toFixed(digits) : "–";
}

/** A `MeanSe` as "mean ± se" (the se left out for one participant). */
function meanSe(m, digits = 1) {
  if (!m || !finite(m.mean)) return "–";
  return m.n > 1 && finite(m.se) ? `${m.mean.toFixed(digits)} ± ${m.se.toFixed(digits)}` : m.mean.toFixed(digits);
}

function pValue(p) {
  if (!finite(p)) return "–";
  return p < 0.001 ? "< 0.001" : p.toFixed(3);
}

function measureName(measure, spec) {
  const fixed = { cumulative_reward: "Cumulative reward", feedback_pct: "Feedback %", seconds: "T (s)", no_feedback: "NFC" };
  if (fixed[measure]) return fixed[measure];
  const id = measure.replace(/^survey\./, "");
  const q = spec.survey.find((x) => x.id === id);
  return `Survey ${id}${q ? `: ${q.text}` : ""}`;
}

function metric(dl, label, value) {
  const d = document.createElement("div");
  d.append(text("dt", label), text("dd", value));
  dl.append(d);
}

// ---- the parts ------------------------------------------------------------------------------

function showSummary(detail, results) {
  const spec = detail.spec;
  $("title").textContent = detail.title;
  document.title = `${detail.title} · results`;
  const dl = $("metrics");
  dl.replaceChildren();
  metric(dl, "Participants", String(results.participants));
  metric(dl, "Complete", String(results.complete));
  metric(dl, "Ordering", spec.ordering ?? "williams");
  const budget = spec.budget ?? {};
  metric(dl, "Budget", budget.steps ? `${budget.steps} steps` : budget.queries ? `${budget.queries} queries` : "the task's");
  metric(dl, "Main contrast", results.main_contrast.join(" vs "));
  const href = new URL(detail.link, location.origin).href;
  $("study-link").href = href;
  $("study-link").textContent = href;
}

function showConditions(spec, results) {
  const head = ["Condition", "n", "Ended early", "Cumulative reward", "Feedback %", "T (s)", "NFC", ...spec.survey.map((q) => `${q.id} (median)`)];
  const tr = document.createElement("tr");
  tr.append(...head.map((h, i) => text("th", h, i === 0 ? "" : "num")));
  document.querySelector("#conditions thead").replaceChildren(tr);
  document.querySelector("#conditions tbody").replaceChildren(
    ...results.conditions.map((c) => {
      const row = document.createElement("tr");
      row.dataset.condition = c.name;
      const cells = [
        [c.name, ""],
        [String(c.n), "num n"],
        [String(c.ended_early), "num ended-early"],
        [meanSe(c.cumulative_reward, 1), "num reward"],
        [meanSe(c.feedback_pct, 1), "num feedback"],
        [meanSe(c.seconds, 1), "num seconds"],
        [meanSe(c.no_feedback, 1), "num nfc"],
        ...spec.survey.map((q) => [num(c.survey[q.id]?.median, 1), "num survey"]),
      ];
      row.append(...cells.map(([v, cls]) => text("td", v, cls)));
      return row;
    }),
  );
}

function showCurves(results) {
  const series = results.conditions.map((c) => {
    const { steps, mean, se } = c.curve;
    return {
      label: c.name,
      points: steps.map((x, i) => [x, mean[i]]),
      band: steps.map((x, i) => [x, mean[i] - (se[i] ?? 0), mean[i] + (se[i] ?? 0)]),
    };
  });
  linePlot($("plot-curves"), results.participants ? series : [], { width: 640, height: 240, xLabel: "steps", empty: "nobody has trained yet" });
}

/** One condition's answers to one question as small bars, 1 to points. */
function bars(counts, top) {
  const w = 150;
  const h = 70;
  const slot = w / counts.length;
  const svg = svgEl("svg", { viewBox: `0 0 ${w} ${h}`, role: "img" });
  counts.forEach((n, i) => {
    const height = top ? ((h - 26) * n) / top : 0;
    const x = i * slot + 3;
    svg.append(svgEl("rect", { x, y: h - 14 - height, width: slot - 6, height, class: "bar" }));
    svg.append(svgEl("text", { x: x + (slot - 6) / 2, y: h - 3, "text-anchor": "middle", class: "tick" }, String(i + 1)));
    if (n) svg.append(svgEl("text", { x: x + (slot - 6) / 2, y: h - 17 - height, "text-anchor": "middle", class: "tick" }, String(n)));
  });
  svg.setAttribute("aria-label", `answers 1 to ${counts.length}: ${counts.join(", ")}`);
  return svg;
}

function showSurvey(spec, results) {
  $("survey").replaceChildren(
    ...spec.survey.map((q) => {
      const box = document.createElement("div");
      box.dataset.question = q.id;
      box.append(text("p", `${q.id}: ${q.text}`, "question"), text("p", `1 = ${q.low}, ${q.points} = ${q.high}`, "muted small"));
      const grid = document.createElement("div");
      grid.className = "dist";
      const top = Math.max(1, ...results.conditions.map((c) => Math.max(0, ...(c.survey[q.id]?.counts ?? []))));
      for (const c of results.conditions) {
        const s = c.survey[q.id] ?? { n: 0, median: null, counts: [] };
        const fig = document.createElement("figure");
        fig.dataset.condition = c.name;
        fig.append(text("figcaption", `${c.name} · n ${s.n} · median ${num(s.median, 1)}`), bars(s.counts, top));
        grid.append(fig);
      }
      box.append(grid);
      return box;
    }),
  );
}

function showTests(spec, results) {
  const names = results.conditions.map((c) => c.name);
  // A caution most measures share (too few participants) is said once, above the table.
  const cautions = results.tests.map((t) => t.tests.caution).filter(Boolean);
  const shared = cautions.length > 1 && cautions.every((c) => c === cautions[0]) ? cautions[0] : null;
  $("tests-caution").textContent = shared ?? "";
  $("tests-caution").classList.toggle("hidden", !shared);
  document.querySelector("#tests tbody").replaceChildren(
    ...results.tests.map(({ measure, tests }) => {
      const tr = document.createElement("tr");
      tr.dataset.measure = measure;
      const f = tests.friedman;
      const pairs = document.createElement("td");
      for (const p of tests.pairs) {
        pairs.append(text("div", `${names[p.a]} vs ${names[p.b]}: p ${pValue(p.p_holm)}; r ${num(p.test?.rank_biserial, 2)}`, "small"));
      }
      if (tests.caution && tests.caution !== shared) pairs.append(text("div", tests.caution, "caution"));
      if (tests.dropped) pairs.append(text("div", `${tests.dropped} participant(s) left out: a condition missing`, "muted small"));
      tr.append(
        text("td", measureName(measure, spec)),
        text("td", String(tests.participants), "num"),
        text("td", f ? `${num(f.statistic, 2)} (${f.df})` : "–", "num"),
        text("td", f ? pValue(f.p) : "–", "num friedman-p"),
        text("td", f ? num(f.kendall_w, 2) : "–", "num"),
        pairs,
      );
      return tr;
    }),
  );
}

function stepWords(step, ordering) {
  switch (step.step) {
    case "consent":
      return "reading the consent";
    case "ready":
      return `about to start ${ordering[step.position]} (${step.position + 1})`;
    case "training":
      return `training ${ordering[step.position]} (${step.position + 1})`;
    case "survey":
      return `survey after ${ordering[step.position]}${step.ended_early ? " (ended early)" : ""}`;
    case "done":
      return "done";
    default:
      return step.step;
  }
}

function showParticipants(detail) {
  const rows = detail.participants_detail;
  document.querySelector("#participants tbody").replaceChildren(
    ...rows.map((p) => {
      const tr = document.createElement("tr");
      tr.dataset.participant = p.id;
      tr.append(text("td", p.id), text("td", String(p.number + 1), "num"), text("td", p.ordering.join(" → ")), text("td", stepWords(p.step, p.ordering)));
      return tr;
    }),
  );
  $("participants-empty").classList.toggle("hidden", rows.length > 0);
}

// ---- loading --------------------------------------------------------------------------------

function showLogin() {
  $("login").classList.remove("hidden");
  $("content").classList.add("hidden");
  document.body.dataset.state = "login";
}

async function load() {
  clearTimeout(pollTimer);
  let detail;
  let results;
  try {
    [detail, results] = await Promise.all([getJson(api), getJson(`${api}/results`)]);
  } catch (e) {
    if (e instanceof ApiError && e.status === 401) {
      notify(e.message, { kind: "error", key: "load" });
      showLogin();
      return;
    }
    notify(`The study could not be loaded: ${e.message}`, { kind: "error", key: "load" });
    if (!(e instanceof ApiError && e.status === 404)) pollTimer = setTimeout(load, POLL_MS);
    return;
  }
  $("login").classList.add("hidden");
  $("content").classList.remove("hidden");
  showSummary(detail, results);
  showConditions(detail.spec, results);
  showCurves(results);
  showSurvey(detail.spec, results);
  showTests(detail.spec, results);
  showParticipants(detail);
  $("updated").textContent = `updated ${new Date().toLocaleTimeString()}`;
  document.body.dataset.state = "loaded";
  document.body.dataset.participants = String(results.participants);
  pollTimer = setTimeout(load, POLL_MS);
}

function table(format) {
  return async () => {
    try {
      await download(`${api}/table?format=${format}`, `study-${studyId}.${format}`);
    } catch (e) {
      notify(`The ${format} table could not be downloaded: ${e.message}`, { kind: "error" });
    }
  };
}

function start() {
  $("login-form").addEventListener("submit", (ev) => {
    ev.preventDefault();
    setToken($("token").value.trim());
    load();
  });
  $("download-csv").addEventListener("click", table("csv"));
  $("download-parquet").addEventListener("click", table("parquet"));
  if (!studyId) {
    notify("No study in the address: /study.html?id=STUDY (the dashboard links each study).", { kind: "error", timeoutMs: 0 });
    document.body.dataset.state = "error";
    return;
  }
  if (!getToken()) {
    showLogin();
    return;
  }
  load();
}

start();
