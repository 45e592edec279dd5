// Two named trainers on one DREF session that takes two answers per query (k = 2, majority):
// the researcher invites Ada from the dashboard (her own link), Bo names himself on the shared
// link; both answer the same queries with the keys; both answers are stored with their names,
// the combined answer is the learner's, and the review page shows how much they agreed.

import { api, check, nextQueryId, newPage, run, shot, waitFor } from "./lib.mjs";

await run("two_trainers", async (browser) => {
  const created = await api("/api/sessions", {
    method: "POST",
    body: {
      task: "reaching", method: "dref", trainer: "human", seed: 4, steps: 3000,
      params: { pace_hz: 1000, answer_timeout_s: 60, answers_per_query: 2, combine: "majority", hidden: [32, 32], batch_size: 32 },
    },
  });

  // The researcher invites Ada from the dashboard.
  const dash = await newPage(browser);
  await dash.goto("/");
  await dash.waitForSelector(`#sessions tr[data-id="${created.id}"] td`);
  await dash.click(`#sessions tr[data-id="${created.id}"] td`);
  await dash.waitForSelector("#invite-box:not(.hidden)");
  await dash.fill("#invite-name", "Ada");
  await dash.click("#invite");
  const adaLink = await dash.locator('#trainer-links li[data-trainer="Ada"] a.trainer-link').getAttribute("href", { timeout: 15_000 });
  check(new URL(adaLink).searchParams.get("token") !== new URL(created.trainer_url, adaLink).searchParams.get("token"), "Ada's link has a token of her own");
  await shot(dash, "dashboard-invite");

  const ada = await newPage(browser, { token: null });
  await ada.goto(adaLink);
  await ada.waitForFunction(() => document.body.dataset.trainer === "Ada");
  check(await ada.locator("#name-form").isHidden(), "an invited trainer is not asked her name");

  // Bo opens the shared link and gives his name.
  const bo = await newPage(browser, { token: null });
  await bo.goto(created.trainer_url);
  await bo.waitForSelector("#name-form:not(.hidden)");
  await bo.fill("#name", "Bo");
  await bo.click("#join");
  await bo.waitForFunction(() => document.body.dataset.trainer === "Bo");
  check(new URL(bo.url()).searchParams.get("token") !== new URL(created.trainer_url, bo.url()).searchParams.get("token"), "Bo's page moved to a link of his own");

  // The same three queries to both: Ada +1, -1, +1; Bo +1, -1, no feedback.
  const plan = [["ArrowUp", "ArrowUp"], ["ArrowDown", "ArrowDown"], ["ArrowUp", "Space"]];
  const asked = [];
  let previous = null;
  for (const [i, [adaKey, boKey]] of plan.entries()) {
    const qid = await nextQueryId(ada, "evaluative", previous, 90_000);
    check((await nextQueryId(bo, "evaluative", previous, 30_000)) === qid, "both are asked the same query");
    asked.push(qid);
    await ada.keyboard.press(adaKey);
    await ada.waitForSelector(`#history li[data-query-id="${qid}"]`, { timeout: 20_000 });
    if (i === 0) await shot(bo, "trainer-second-of-two");
    await bo.keyboard.press(boKey);
    await bo.waitForSelector(`#history li[data-query-id="${qid}"]`, { timeout: 20_000 });
    previous = qid;
  }
  await api(`/api/sessions/${created.id}/stop`, { method: "POST" });

  // Both answers stored with their names; the learner took the majority.
  const answers = await api(`/api/sessions/${created.id}/answers`);
  const majority = [1, -1, 0];
  for (const [i, qid] of asked.entries()) {
    const a = answers.find((x) => x.query_id === qid);
    check(a && a.who === "trainers" && a.value === majority[i], `query ${qid}: ${JSON.stringify(a)}`);
  }
  const trainers = await api(`/api/sessions/${created.id}/trainers`);
  const byName = Object.fromEntries(trainers.map((t) => [t.name, t]));
  check(byName.Ada?.answers === 3 && byName.Bo?.answers === 3, `answers per trainer: ${JSON.stringify(trainers)}`);
  check(byName.Bo.no_feedback === 1 && byName.Ada.no_feedback === 0, "NFC per trainer");
  check(byName.Ada.origin === "invited" && byName.Bo.origin === "joined", "how each came");
  const exported = await (await fetch(new URL(`/api/sessions/${created.id}/export?format=jsonl`, process.env.DUALREP_URL), { headers: { Authorization: `Bearer ${process.env.DUALREP_TOKEN}` } })).text();
  const own = exported.trim().split("\n").map((l) => JSON.parse(l)).filter((r) => r.record === "trainer_answer");
  check(own.length === 6, `six answers of their own in the export, got ${own.length}`);
  const agreement = await api(`/api/sessions/${created.id}/agreement`);
  check(agreement.measure === "krippendorff_alpha_ordinal" && agreement.units === 3, JSON.stringify(agreement));
  check(Math.abs(agreement.value - 7 / 9) < 1e-9, `alpha ${agreement.value}, expected 7/9`);

  // The review page shows both trainers and their agreement.
  const review = await newPage(browser);
  await review.goto(`/review/${created.id}`);
  await waitFor("the review's trainers", async () => (await review.locator("#trainers tbody tr").count()) >= 2);
  check((await review.locator('#trainers tbody tr[data-trainer="Ada"]').count()) === 1, "Ada on the review page");
  check((await review.locator('#trainers tbody tr[data-trainer="Bo"]').count()) === 1, "Bo on the review page");
  const shown = await review.locator("#agreement-value").textContent();
  check(shown === agreement.value.toFixed(3), `agreement shown ${shown}, API ${agreement.value}`);
  check((await review.locator("#pairs tbody tr").count()) === 1, "one pair of trainers");
  check((await review.locator("#answers tbody").textContent()).includes("trainers"), "combined answers say so");
  await shot(review, "review-two-trainers");
  for (const p of [dash, ada, bo, review]) p.assertNoErrors();
});
