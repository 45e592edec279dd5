// Launch a human DREF session on Reaching from the dashboard, answer its queries in the trainer
// page with the keys (up, space, down), undo the last with U and answer it again, and find the
// answers in /api/sessions/{id}/answers.

import { api, check, nextQueryId, newPage, run, shot, waitFor } from "./lib.mjs";

await run("dref_keys", async (browser) => {
  const page = await newPage(browser, { token: null });
  await page.goto("/");
  await page.waitForSelector("#login:not(.hidden)");
  await shot(page, "dashboard-login");
  await page.fill("#token", process.env.DUALREP_TOKEN);
  await page.keyboard.press("Enter");
  await page.waitForSelector("#app:not(.hidden)");
  await page.waitForSelector("#task option[value=reaching]", { state: "attached" });

  // The launch form: small, fast, with the advanced parameters.
  await page.selectOption("#task", "reaching");
  await page.selectOption("#method", "dref");
  await page.selectOption("#trainer", "human");
  await page.fill("#seed", "0");
  await page.fill("#budget", "3000");
  await page.fill("#pace_hz", "1000");
  await page.fill("#answer_timeout_s", "60");
  await page.click("#advanced summary");
  check(await page.locator("#params input").count() > 0, "advanced parameters are listed with their defaults");
  await page.fill("#extra", '{"hidden": [32, 32], "batch_size": 32}');
  await shot(page, "dashboard-launch-form");
  await page.click("#launch");
  const link = page.locator("#trainer-link");
  await link.waitFor();
  const href = await link.getAttribute("href");
  const id = decodeURIComponent(new URL(href).pathname.split("/")[2]);
  check(new URL(href).searchParams.get("token"), "the trainer link carries a token");
  await page.waitForSelector(`#sessions tr[data-id="${id}"]`);

  // The trainer page, keyboard only.
  const trainer = await newPage(browser, { token: null });
  await trainer.goto(href);
  const keys = [["ArrowUp", 1], ["Space", 0], ["ArrowDown", -1]];
  const asked = [];
  let previous = null;
  for (const [i, [key]] of keys.entries()) {
    const qid = await nextQueryId(trainer, "evaluative", previous, 90_000);
    if (i === 0) {
      await trainer.waitForTimeout(600); // let the clip loop reach its last frame once
      await shot(trainer, "trainer-evaluative");
    }
    asked.push(qid);
    await trainer.keyboard.press(key);
    await trainer.waitForSelector(`#history li[data-query-id="${qid}"]`, { timeout: 20_000 });
    previous = qid;
  }
  await shot(trainer, "trainer-after-answers");

  // Undo the last answer with U: the same query comes back and takes a new answer.
  const last = asked[asked.length - 1];
  await trainer.keyboard.press("u");
  await trainer.waitForSelector(`#history li.undone[data-query-id="${last}"]`, { timeout: 20_000 });
  await trainer.waitForFunction(
    (qid) => document.querySelector("#evaluative")?.dataset.queryId === String(qid) && document.body.dataset.state === "query",
    last,
    { timeout: 20_000 },
  );
  await shot(trainer, "trainer-undone");
  await trainer.keyboard.press("ArrowUp");
  await trainer.waitForSelector(`#history li:not(.undone)[data-query-id="${last}"]`, { timeout: 20_000 });
  const expected = [1, 0, 1]; // the last one as given again after the undo

  const answers = await api(`/api/sessions/${id}/answers`);
  for (const [i] of keys.entries()) {
    const a = answers.find((x) => x.query_id === asked[i]);
    const value = expected[i];
    check(a, `query ${asked[i]} has a stored answer`);
    check(a.value === value, `query ${asked[i]}: stored ${JSON.stringify(a.value)}, the keys meant ${value}`);
    check(a.revision === (asked[i] === last ? 2 : 0), `query ${asked[i]}: revision ${a.revision}`);
    check(a.who === "trainer", `query ${asked[i]} was answered by the trainer (who = ${a.who})`);
    check(a.kind === "evaluative" && Number.isFinite(a.latency_ms), "answers carry kind and latency");
  }

  // A tablet-sized trainer page, and the dashboard with the live session.
  await trainer.setViewportSize({ width: 820, height: 1180 });
  await trainer.waitForTimeout(300);
  await shot(trainer, "trainer-tablet");
  await page.click(`#sessions tr[data-id="${id}"] td`);
  await page.waitForSelector("#detail:not(.hidden)");
  await shot(page, "dashboard-sessions");
  // A synthetic DRPL session's alignment curve, whole, on the dashboard.
  const pref = await api("/api/sessions", {
    method: "POST",
    body: { task: "reaching", method: "drpl", trainer: "synthetic", seed: 2, queries: 8, params: { trajectories: 12 } },
  });
  await waitFor("the DRPL session to finish", async () => (await api(`/api/sessions/${pref.id}`)).status === "finished");
  await page.waitForSelector(`#sessions tr[data-id="${pref.id}"] td`);
  await page.click(`#sessions tr[data-id="${pref.id}"] td`);
  await page.waitForFunction(() => document.querySelectorAll("#plot-alignment svg polyline, #plot-alignment svg path").length >= 2, null, { timeout: 15_000 });
  await shot(page, "dashboard-alignment");
  await page.click(`#sessions tr[data-id="${id}"] td`);
  await api(`/api/sessions/${id}/stop`, { method: "POST" });
  await page.waitForSelector(`#sessions tr[data-id="${id}"] .pill.stopped`, { timeout: 15_000 });
  trainer.assertNoErrors();
  page.assertNoErrors();
});
