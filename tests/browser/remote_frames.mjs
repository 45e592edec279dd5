// A remote env's own task from the dashboard: launch a human DREF session on the env at
// $ENV_URL (Gymnasium's Pendulum-v1 served by `python -m dualrep.env`), then check that the
// trainer page draws the env's own frames (its PNG images) in the live view and in the query's
// clip, and that an answer given with a key is stored.

import { api, check, nextQueryId, newPage, run, shot } from "./lib.mjs";

const ENV_URL = process.env.ENV_URL;
check(ENV_URL, "ENV_URL names the env server");

/** Pixels of the first canvas in `selector` that differ from the stage's background. */
async function drawnPixels(page, selector) {
  return page.evaluate((sel) => {
    const canvas = document.querySelector(`${sel} canvas`);
    if (!canvas || !canvas.width) return 0;
    const data = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
    let n = 0;
    // The background is #1d2535; Pendulum's frames are white with a red rod.
    for (let i = 0; i < data.length; i += 4) if (data[i] > 200 && data[i + 1] > 200 && data[i + 2] > 200) n++;
    return n;
  }, selector);
}

await run("remote_frames", async (browser) => {
  const page = await newPage(browser);
  await page.goto("/");
  await page.waitForSelector("#app:not(.hidden)");
  await page.waitForSelector("#task option[value=remote]", { state: "attached" });
  await page.selectOption("#task", "remote");
  await page.fill("#env_url", ENV_URL);
  await page.selectOption("#method", "dref");
  await page.selectOption("#trainer", "human");
  await page.fill("#budget", "600");
  await page.fill("#pace_hz", "50");
  await page.click("#advanced summary");
  await page.fill("#extra", '{"hidden": [16, 16], "batch_size": 32}');
  await page.click("#launch");
  const link = page.locator("#trainer-link");
  await link.waitFor();
  const href = await link.getAttribute("href");
  const id = decodeURIComponent(new URL(href).pathname.split("/")[2]);
  await page.waitForSelector(`#sessions tr[data-id="${id}"]`);
  check((await page.locator(`#sessions tr[data-id="${id}"]`).innerText()).includes(ENV_URL), "the sessions list names the env");

  const trainer = await newPage(browser, { token: null });
  await trainer.goto(href);
  const qid = await nextQueryId(trainer, "evaluative", null, 90_000);
  await trainer.waitForFunction(() => document.querySelector("#eval-stage canvas")?.dataset.drawn, null, { timeout: 10_000 });
  await trainer.waitForTimeout(500); // the clip's frames decode and loop
  const inClip = await drawnPixels(trainer, "#eval-stage");
  check(inClip > 1000, `the query's clip shows the env's frame (${inClip} light pixels)`);
  check((await trainer.locator("#action-words").innerText()).includes("acts ["), "the action is given in numbers");
  await shot(trainer, "trainer-remote-frames");
  await trainer.keyboard.press("ArrowUp");
  await trainer.waitForSelector(`#history li[data-query-id="${qid}"]`, { timeout: 20_000 });
  const answers = await api(`/api/sessions/${id}/answers`);
  check(answers.some((a) => a.query_id === qid && a.value === 1), `query ${qid} is stored as good`);
  await api(`/api/sessions/${id}/stop`, { method: "POST" });
  trainer.assertNoErrors();
  page.assertNoErrors();
});
