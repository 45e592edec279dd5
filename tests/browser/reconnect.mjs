// Drop the trainer's websocket while a query waits: the page reconnects by itself, shows the
// same pending query again, and an answer given after the drop is stored.

import { api, check, nextQueryId, newPage, run, shot } from "./lib.mjs";

await run("reconnect", async (browser) => {
  const created = await api("/api/sessions", {
    method: "POST",
    body: { task: "reaching", method: "dref", trainer: "human", seed: 2, steps: 3000, params: { pace_hz: 1000, answer_timeout_s: 120, hidden: [32, 32], batch_size: 32 } },
  });
  const page = await newPage(browser, { token: null });
  const sockets = [];
  // Every socket goes through this proxy, so the test can cut the page's side.
  await page.routeWebSocket(/\/ws\/sessions\//, (ws) => {
    const server = ws.connectToServer();
    sockets.push({ ws, server });
  });
  await page.goto(created.trainer_url);
  const qid = await nextQueryId(page, "evaluative", null, 90_000);
  check(sockets.length === 1, `one socket before the drop (${sockets.length})`);
  const { ws, server } = sockets[0];
  server.close();
  ws.close({ code: 4000, reason: "dropped by the test" });
  await page.waitForFunction(() => document.body.dataset.connection === "reconnecting", null, { timeout: 10_000 });
  await shot(page, "trainer-reconnecting");
  await page.waitForFunction(() => document.body.dataset.connection === "connected", null, { timeout: 20_000 });
  check(sockets.length >= 2, "the page opened a new socket");
  const again = await nextQueryId(page, "evaluative", null, 20_000);
  check(again === qid, `the pending query ${qid} is shown again after reconnecting (got ${again})`);
  await shot(page, "trainer-resumed");
  await page.keyboard.press("ArrowDown");
  await page.waitForSelector(`#history li[data-query-id="${qid}"]`, { timeout: 20_000 });
  const answers = await api(`/api/sessions/${created.id}/answers`);
  const a = answers.find((x) => x.query_id === qid);
  check(a && a.value === -1 && a.who === "trainer", `the answer after the drop is stored: ${JSON.stringify(a)}`);
  await api(`/api/sessions/${created.id}/stop`, { method: "POST" });
  page.assertNoErrors();
});
