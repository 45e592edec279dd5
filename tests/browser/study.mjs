// A within-subject study in the browser: the researcher creates one from the dashboard (DREF, EF-50 and SAC on
// Reaching); three people open its one link at the same time (separate browsers), consent, and
// for each condition in their Williams order start it (one of the three waits in the queue:
// the server runs two sessions at once), train in the trainer page answering every query with
// the keys, continue back to the study and answer its survey, until done. One of them reloads
// the trainer page and then the study page mid-condition and carries on in the same session;
// another sends an out-of-range answer from the page and sees the server's message. The results
// page shows n = 3 per condition and downloads the Parquet table (the Rust test reads it with
// pyarrow: 9 rows).

import { join } from "node:path";
import { ARTIFACTS, BASE, api, check, newPage, run, shot, waitFor } from "./lib.mjs";

const NAMES = ["dref", "ef-50", "sac"];
// server/study/ordering.rs williams_rows(3): the square, then its mirror; participant i: row i mod 6.
const WILLIAMS = [[0, 1, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0], [0, 2, 1], [1, 0, 2]];
const KEYS = ["ArrowUp", "Space", "ArrowDown"];
const PARTICIPANTS = 3;

const started = Date.now();
const log = (...args) => console.log(`[${((Date.now() - started) / 1000).toFixed(1)} s]`, ...args);

/** Resolves once `n` callers are waiting: the participants press "Start" together. */
function barrier(n) {
  let waiting = 0;
  let release;
  const all = new Promise((r) => {
    release = r;
  });
  return () => {
    waiting += 1;
    if (waiting === n) release();
    return all;
  };
}

async function step(page, name, timeout = 60_000) {
  try {
    await page.waitForFunction((s) => document.body.dataset.step === s, name, { timeout });
  } catch (e) {
    // Say where the page is instead, and what it told the person (a refused request's message).
    const at = await page.evaluate(() => ({ step: document.body.dataset.step, messages: [...document.querySelectorAll("#messages .message")].map((m) => m.textContent) }));
    throw new Error(`waiting for the step ${name}: the page is at ${at.step}, showing ${JSON.stringify(at.messages)}; page errors ${JSON.stringify(page.errors)}\n${e.message}`);
  }
}

async function participantView(link, token) {
  const res = await fetch(new URL(`/api/study-links/${link}/participants/${token}`, BASE));
  check(res.ok, `GET participant: ${res.status}`);
  return res.json();
}

/**
 * Answers every query on the trainer page with the keys, in turn up / space / down, until the
 * session ends; `after(n)` runs after the n-th answer. Returns the number of answers.
 */
async function answerUntilEnd(page, after = async () => {}) {
  let previous = null;
  let n = 0;
  for (;;) {
    const handle = await page.waitForFunction(
      (not) => {
        if (document.body.dataset.state === "ended") return { ended: true };
        const el = document.querySelector("#evaluative");
        const id = el?.dataset.queryId;
        return id && id !== not && !el.classList.contains("hidden") && document.body.dataset.state === "query" ? { id } : null;
      },
      previous,
      { timeout: 90_000, polling: 20 },
    );
    const got = await handle.jsonValue();
    if (got.ended) return n;
    await page.keyboard.press(KEYS[n % KEYS.length]);
    await page.waitForFunction(
      (id) => document.body.dataset.state === "ended" || document.querySelector(`#history li[data-query-id="${id}"]`),
      got.id,
      { timeout: 20_000, polling: 20 },
    );
    previous = got.id;
    n += 1;
    await after(n);
  }
}

await run("study", async (browser) => {
  const fast = { pace_hz: 1000, answer_timeout_s: 60, record: false };
  const small = { ...fast, hidden: [32, 32], batch_size: 32 };
  const spec = {
    title: "Teaching a robot arm",
    conditions: [
      { name: "dref", task: "reaching", method: "dref", params: small },
      { name: "ef-50", task: "reaching", method: "ef-50", params: small },
      // SAC asks nothing, so nothing holds its session back: at 1000 steps a second its 300
      // steps could end (and the study page move on to the survey) before the participant has
      // opened it, as happened once under CI load. At 30 a second it lasts ten seconds.
      { name: "sac", task: "reaching", method: "sac", params: { ...small, pace_hz: 30 } },
    ],
    budget: { steps: Number(process.env.STUDY_STEPS || 300) },
  };

  // The researcher creates the study from the dashboard's form (a bad one first: the server's
  // message reaches the page and nothing is created).
  const dash = await newPage(browser);
  await dash.goto("/");
  await dash.click("#new-study summary");
  check((await dash.inputValue("#study-spec")).includes('"method": "dref"'), "the form starts from the paper's design");
  await dash.fill("#study-spec", JSON.stringify({ ...spec, survey: [] }));
  await dash.click("#create-study");
  await dash.waitForSelector(".message.error >> text=survey: needs at least one question");
  check((await api("/api/studies")).length === 0, "a refused study is not stored");
  // Chromium logs the refused request itself; that is expected here.
  const refused = (e) => e.includes("status of 422");
  check(dash.errors.some(refused), "the refused request was made");
  dash.errors.splice(0, dash.errors.length, ...dash.errors.filter((e) => !refused(e)));
  await dash.fill("#study-spec", JSON.stringify(spec, null, 2));
  await dash.click("#create-study");
  await dash.waitForSelector(".message.ok >> text=Send this link to every participant");
  const [study] = await api("/api/studies");
  check(study && study.title === spec.title, "the dashboard created the study");
  const link = study.link.split("/").pop();
  log(`study ${study.id}, link ${study.link}`);

  // The dashboard lists it with its participant link and its results page.
  await dash.waitForSelector(`#studies li[data-study="${study.id}"]`);
  check((await dash.locator(`#studies li[data-study="${study.id}"] a.study-link`).getAttribute("href")) === new URL(study.link, BASE).href, "the dashboard shows the participant link");
  check((await dash.locator(`#studies li[data-study="${study.id}"] a.study-results`).getAttribute("href")) === `/study.html?id=${study.id}`, "the dashboard links the results page");

  const startTogether = barrier(PARTICIPANTS);
  const seen = { queued: 0, reloaded: false, badAnswer: false };
  const people = [];

  async function participate(index) {
    const page = await newPage(browser, { token: null });
    people.push(page);
    // The one study link, no token: the page joins and moves to the participant's own link.
    await page.goto(study.link);
    await step(page, "consent");
    const token = new URL(page.url()).searchParams.get("participant");
    check(token, `participant ${index}: the page moved to a link of their own (${page.url()})`);
    check((await page.evaluate((k) => localStorage.getItem(k), `dualrep.study.${link}`)) === token, "the token is kept in this browser");
    const view = await participantView(link, token);
    const labels = await page.locator("#conditions li .name").allTextContents();
    check(JSON.stringify(labels) === JSON.stringify(view.labels) && labels.every((l) => /^Method [ABC]$/.test(l)), `participants see labels, not method names: ${labels}`);
    const shown = await page.locator("#conditions li").evaluateAll((els) => els.map((e) => e.dataset.condition));
    check(JSON.stringify(shown) === JSON.stringify(view.ordering), `the page shows the participant's order ${shown} = ${view.ordering}`);
    check((await page.locator("#consent-text").textContent()) === view.consent, "the consent text is shown");
    check((await page.locator("#own-link").getAttribute("href")) === new URL(view.url, BASE).href, "the participant's own link is shown");
    if (index === 0) await shot(page, "study-consent");
    await page.click("#agree");

    for (const [position, condition] of view.ordering.entries()) {
      await step(page, "ready");
      check((await page.locator("#conditions li.current").getAttribute("data-position")) === String(position), `position ${position} is highlighted`);
      check((await page.locator("#conditions li.done").count()) === position, `${position} sessions ticked`);
      if (position === 0) await startTogether();
      await page.click("#start");
      await step(page, "training");
      const status = await page.locator("#queue").getAttribute("data-status");
      if (status === "queued") {
        seen.queued += 1;
        const first = seen.queued === 1;
        const words = await page.locator("#queue").textContent();
        check(/yours is next|before yours/.test(words), `the queue is shown: ${words}`);
        if (first) await shot(page, "study-queued");
      }
      const href = await page.locator("#train-link").getAttribute("href");
      const own = new URL(page.url());
      check(href.endsWith(`&next=${encodeURIComponent(own.pathname + own.search)}`), `the trainer link comes back to the study: ${href}`);
      const sessionId = (await participantView(link, token)).step.session_id;
      check(href.startsWith(`/train/${sessionId}?token=`), `the trainer link is the session's (${sessionId})`);
      await page.click("#train-link");
      await page.waitForURL(/\/train\//);
      check(new URL(page.url()).searchParams.get("next") === own.pathname + own.search, "next= arrives on the trainer page");
      await page.waitForFunction(() => document.getElementById("title").textContent !== "Teach the robot");
      const heading = await page.locator("#title").textContent();
      check(!heading.toLowerCase().includes(condition), `the trainer page does not name the method: ${heading}`);

      // The first participant reloads mid-condition in EF-50 (it asks on half the steps): the
      // trainer page, then the study page from the bare study link; the same session goes on.
      const reload = index === 0 && condition === "ef-50";
      const answers = await answerUntilEnd(page, async (n) => {
        if (!reload) return;
        if (n === 2) {
          const before = page.url();
          await page.reload();
          check(page.url() === before, "the trainer page reloads on the same link");
          log(`participant ${index}: reloaded the trainer page`);
        } else if (n === 4) {
          await page.goto(study.link);
          await step(page, "training");
          check(new URL(page.url()).searchParams.get("participant") === token, "the bare link finds the participant kept in this browser");
          await page.reload();
          await step(page, "training");
          check((await participantView(link, token)).step.session_id === sessionId, "still the same session");
          check((await page.locator("#train-link").getAttribute("href")) === href, "the same trainer link");
          await page.click("#train-link");
          await page.waitForURL(/\/train\//);
          check(page.url().includes(`/train/${sessionId}?`), "back in the same session");
          seen.reloaded = true;
          log(`participant ${index}: reloaded the study page`);
        }
      });
      log(`participant ${index}: ${condition} ended after ${answers} answers`);
      if (condition === "ef-50") check(answers > 4, `EF-50 asked ${answers} queries`);
      if (condition === "sac") check(answers === 0, "SAC asks nothing");
      check(await page.locator("#survey").isHidden(), "a study's session does not ask the trainer page's three questions");
      check(await page.locator("#name-form").isHidden(), "nor a name");
      await page.click("#continue");

      await step(page, "survey");
      const title = await page.locator("#survey-title").textContent();
      check(title.includes(view.labels[position]) && !title.includes(condition), `the survey names ${view.labels[position]}, not ${condition}: ${title}`);
      check(await page.locator("#ended-early").isHidden(), "the session ran to its end");
      const questions = await page.locator("#survey-form fieldset").evaluateAll((els) => els.map((e) => e.dataset.question));
      check(JSON.stringify(questions) === JSON.stringify(view.survey.map((q) => q.id)), `every question is asked: ${questions}`);
      for (const [q, id] of questions.entries()) {
        const value = ((index + position + q) % 5) + 1;
        await page.check(`#survey-form fieldset[data-question="${id}"] input[value="${value}"]`);
      }
      if (index === 1 && position === 0) {
        // A value off the scale (the radios cannot send one): the server's message is shown.
        await page.evaluate(() => {
          const input = document.querySelector("#survey-form fieldset input:checked");
          input.dataset.was = input.value;
          input.value = "9";
        });
        await page.click("#survey-form button[type=submit]");
        const message = page.locator("#messages .message.error", { hasText: "must be 1 to 5, got 9" });
        await message.waitFor({ timeout: 10_000 });
        check((await page.evaluate(() => document.body.dataset.step)) === "survey", "still at the survey");
        await page.evaluate(() => {
          const input = document.querySelector("#survey-form fieldset input:checked");
          input.value = input.dataset.was;
        });
        // Chromium logs the refused request itself; that is expected here.
        const expected = (e) => e.includes("status of 400");
        check(page.errors.some(expected), "the refused request was made");
        page.errors.splice(0, page.errors.length, ...page.errors.filter((e) => !expected(e)));
        seen.badAnswer = true;
      }
      if (index === 0 && position === 0) await shot(page, "study-survey");
      await page.click("#survey-form button[type=submit]");
      await step(page, position + 1 < view.ordering.length ? "ready" : "done");
    }
    check((await page.locator("#conditions li.done").count()) === view.ordering.length, "every session ticked");
    if (index === 0) await shot(page, "study-done");
    log(`participant ${index}: done`);
    return { page, token, id: await page.evaluate(() => document.body.dataset.participant), ordering: view.ordering };
  }

  const done = await Promise.all([...Array(PARTICIPANTS).keys()].map(participate));
  check(seen.queued >= 1, "of three starting together with two slots, one waited in the queue");
  check(seen.reloaded, "a participant reloaded mid-condition");
  check(seen.badAnswer, "an out-of-range answer was refused on the page");

  // Each participant's order is their row of the Williams design, by the order they joined.
  const detail = await api(`/api/studies/${study.id}`);
  check(detail.participants === PARTICIPANTS, `${detail.participants} participants`);
  const numbers = [];
  for (const p of done) {
    const row = detail.participants_detail.find((x) => x.id === p.id);
    check(row, `participant ${p.id} is in the study`);
    numbers.push(row.number);
    const expected = WILLIAMS[row.number % WILLIAMS.length].map((i) => NAMES[i]);
    check(JSON.stringify(p.ordering) === JSON.stringify(expected), `participant ${row.number}: ${p.ordering} is Williams row ${expected}`);
    check(JSON.stringify(row.ordering) === JSON.stringify(expected), "the study's record agrees");
    check(row.step.step === "done" && row.sessions.length === 3, `${p.id} is done: ${JSON.stringify(row.step)}`);
  }
  check(JSON.stringify(numbers.sort()) === "[0,1,2]", `participants numbered 0, 1, 2: ${numbers}`);

  // The trainer page ignores a `next` that is not a study path on this server.
  const session = await api(`/api/sessions/${detail.participants_detail[0].sessions[0]}`);
  const stray = await newPage(browser, { token: null });
  await stray.goto(`${session.trainer_url}&next=${encodeURIComponent("//elsewhere.example/study/x")}`);
  await stray.waitForFunction(() => document.body.dataset.state === "ended");
  check(await stray.locator("#continue-box").isHidden(), "no Continue to another site");
  check(await stray.locator("#survey").isVisible(), "the trainer page's own questions instead");

  // The results page: n = 3 everywhere, curves, survey bars, tests; the Parquet table.
  const results = await newPage(browser);
  await results.goto(`/study.html?id=${study.id}`);
  await results.waitForFunction(() => document.body.dataset.state === "loaded");
  const rows = await results.locator("#conditions tbody tr").evaluateAll((trs) => trs.map((tr) => [tr.dataset.condition, tr.querySelector("td.n").textContent, tr.querySelector("td.ended-early").textContent]));
  check(JSON.stringify(rows) === JSON.stringify(NAMES.map((n) => [n, "3", "0"])), `n = 3 per condition: ${JSON.stringify(rows)}`);
  check((await results.locator("#plot-curves svg path.line").count()) === 3, "a curve per condition");
  check((await results.locator("#plot-curves svg path.band").count()) === 3, "a mean ± s.e. band per condition");
  check((await results.locator("#survey figure svg").count()) === 9, "three questions x three conditions of bars");
  const measures = await results.locator("#tests tbody tr").evaluateAll((trs) => trs.map((tr) => tr.dataset.measure));
  check(measures.includes("cumulative_reward") && measures.includes("survey.E"), `tests: ${measures}`);
  check(/n = 3 participants/.test(await results.locator("#tests-caution").textContent()), "three participants come with a caution, said once");
  check((await results.locator("#participants tbody tr").count()) === 3, "three participants listed");
  await shot(results, "study-results");
  const [download] = await Promise.all([results.waitForEvent("download"), results.click("#download-parquet")]);
  check(download.suggestedFilename() === `study-${study.id}.parquet`, download.suggestedFilename());
  const file = join(ARTIFACTS, "study-table.parquet");
  await download.saveAs(file);
  log(`the Parquet table: ${file}`);

  for (const p of [dash, stray, results, ...people]) p.assertNoErrors();
});
