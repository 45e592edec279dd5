// Answer a human DRPL session's preference queries with the mouse; find them in the API. With
// SURVEY=1, also answer the three questions at the end and find them in the session.

import { api, check, nextQueryId, newPage, run, shot, waitFor } from "./lib.mjs";

await run("drpl_mouse", async (browser) => {
  const created = await api("/api/sessions", {
    method: "POST",
    body: { task: "reaching", method: "drpl", trainer: "human", seed: 1, queries: 3, params: { trajectories: 10 } },
  });
  const page = await newPage(browser, { token: null });
  await page.goto(created.trainer_url);
  const buttons = ["left", "right", "equal"];
  const asked = [];
  let previous = null;
  for (const [i, value] of buttons.entries()) {
    const qid = await nextQueryId(page, "preference", previous, 120_000);
    if (i === 0) {
      await page.waitForTimeout(600);
      check(await page.locator("#differ").textContent(), "the differing predicate (or a prompt) is shown");
      await shot(page, "trainer-preference");
    }
    asked.push(qid);
    await page.click(`#answers-pref button[data-value="${value}"]`);
    await page.waitForSelector(`#history li[data-query-id="${qid}"]`, { timeout: 20_000 });
    previous = qid;
  }
  const answers = await api(`/api/sessions/${created.id}/answers`);
  for (const [i, value] of buttons.entries()) {
    const a = answers.find((x) => x.query_id === asked[i]);
    check(a && a.value === value, `query ${asked[i]}: stored ${JSON.stringify(a?.value)}, clicked ${value}`);
    check(a.who === "trainer" && a.kind === "preference", "answered by the trainer, as a preference");
  }
  // Three queries were the budget: the page says the session is over and asks three questions.
  await page.waitForSelector("#survey:not(.hidden)", { timeout: 60_000 });
  await shot(page, "trainer-survey");
  if (process.env.SURVEY === "1") {
    await page.click('fieldset[data-name=overall_experience] input[value="4"]');
    await page.click('fieldset[data-name=perceived_intelligence] input[value="3"]');
    await page.click('fieldset[data-name=cognitive_ease] input[value="5"]');
    await page.click("#survey-form button[type=submit]");
    await page.waitForFunction(() => document.body.dataset.state === "survey-saved", null, { timeout: 10_000 });
    const s = await waitFor("the survey in the session", async () => (await api(`/api/sessions/${created.id}`)).survey);
    check(s.overall_experience === 4 && s.perceived_intelligence === 3 && s.cognitive_ease === 5, `stored survey ${JSON.stringify(s)}`);
    await shot(page, "trainer-survey-saved");
  }
  page.assertNoErrors();
});
