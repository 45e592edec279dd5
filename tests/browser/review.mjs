// A short human DREF session whose queries all time out ("no feedback"): the review page shows
// its episodes with returns, every query's answer and latency, the session's T and NFC, and the
// recording's command. With REPLAY=1 it also replays an episode on the canvas (play, pause,
// step, speed).

import { api, check, newPage, run, shot, waitFor } from "./lib.mjs";

await run("review", async (browser) => {
  const created = await api("/api/sessions", {
    method: "POST",
    body: { task: "lunar-lander", method: "dref", trainer: "human", seed: 3, steps: 200, params: { pace_hz: 1000, answer_timeout_s: 0.3, hidden: [32, 32], batch_size: 32 } },
  });
  const session = await waitFor("the session to finish", async () => {
    const s = await api(`/api/sessions/${created.id}`);
    check(!["failed", "stopped", "interrupted"].includes(s.status), `session ${created.id} ${s.status}: ${s.reason}`);
    return s.status === "finished" ? s : null;
  }, { timeoutMs: 180_000, everyMs: 500 });
  const episodes = await api(`/api/sessions/${created.id}/episodes`);
  const answers = await api(`/api/sessions/${created.id}/answers`);
  check(episodes.length >= 1, "the session finished an episode");
  check(answers.length >= 1, "the session asked at least one query");

  const page = await newPage(browser);
  await page.goto(`/review/${created.id}`);
  await page.waitForSelector("#content:not(.hidden)");
  await page.waitForSelector("#episodes tbody tr");
  check((await page.locator("#episodes tbody tr").count()) === episodes.length, "one row per episode");
  check((await page.locator("#answers tbody tr").count()) === answers.length, "one row per answered query");
  check((await page.locator("#timeline circle").count()) === answers.length, "every answer on the timeline");
  const metrics = await page.locator("#metrics").textContent();
  check(metrics.includes("No feedback (NFC)") && metrics.includes(String(session.answers.no_feedback)), `NFC shown: ${metrics}`);
  check(metrics.includes("Trainer time (T)"), "T shown");
  check((await page.locator("#rerun-cmd").textContent()).includes(`${created.id}.rrd`), "the Rerun command names the file");
  await shot(page, "review");

  if (process.env.REPLAY === "1") {
    await page.click('#episodes tbody tr[data-episode="0"] button');
    await page.waitForFunction(() => document.body.dataset.replay === "playing", null, { timeout: 10_000 });
    await page.waitForFunction(() => Number(document.body.dataset.replayFrame) > 5, null, { timeout: 10_000 });
    await page.keyboard.press("k");
    check((await page.evaluate(() => document.body.dataset.replay)) === "paused", "K pauses");
    const before = Number(await page.evaluate(() => document.body.dataset.replayFrame));
    await page.click("#fwd");
    const after = Number(await page.evaluate(() => document.body.dataset.replayFrame));
    check(after === before + 1, `step forward moves one frame (${before} -> ${after})`);
    await page.selectOption("#speed", "4");
    await shot(page, "review-replay");
  }
  page.assertNoErrors();
});
