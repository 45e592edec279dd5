// A trainer's answer that the server refuses for coming too fast (`rate_limited`, with the
// wait in `retry_after_ms`) is sent again by the page after that wait: the person is not asked
// twice, and the answer is stored once. The test sits between the page and the server and,
// just before the page's answer, spends the socket's whole burst on undos of a query that does
// not exist (their replies are kept from the page), so that the answer finds no token left.

import { api, check, nextQueryId, newPage, run } from "./lib.mjs";

// No query has this id: the server refuses each undo, and the page never sees those replies.
const SPENT = 999_999_999;
// More than the socket's burst (server/ws/rate_limit.rs BURST = 40).
const SPEND = 60;
// The burst is spent only if the server takes the undos less than 50 ms apart (it refills 20 a
// second); a server starved of CPU (CI beside other work) may not, and then the answer goes
// through unrefused. That query proves nothing either way, so the next one is tried, up to
// this many; a page that mishandles a refusal fails the checks below on the one refused.
const ATTEMPTS = 3;

await run("rate_limited", async (browser) => {
  const created = await api("/api/sessions", {
    method: "POST",
    body: { task: "reaching", method: "dref", trainer: "human", seed: 3, steps: 3000, params: { pace_hz: 1000, answer_timeout_s: 120, hidden: [32, 32], batch_size: 32 } },
  });
  const page = await newPage(browser, { token: null });
  const sent = []; // the page's answers: ids, in order
  const refused = []; // rate_limited replies to the page's own answers
  let spent = true; // false: spend the burst just before the page's next answer (each attempt's)
  await page.routeWebSocket(/\/ws\/sessions\//, (ws) => {
    const server = ws.connectToServer();
    ws.onMessage((m) => {
      const msg = JSON.parse(m);
      if (msg.type === "answer") {
        sent.push(msg.id);
        if (!spent) {
          spent = true;
          for (let i = 0; i < SPEND; i += 1) server.send(JSON.stringify({ type: "undo", id: SPENT }));
        }
      }
      server.send(m);
    });
    server.onMessage((m) => {
      const msg = JSON.parse(m);
      if (msg.id === SPENT) return;
      if (msg.type === "error" && msg.code === "rate_limited") refused.push(msg);
      ws.send(m);
    });
  });
  await page.goto(created.trainer_url);
  await page.evaluate(() => {
    window.statesSeen = [];
    new MutationObserver(() => window.statesSeen.push(document.body.dataset.state)).observe(document.body, { attributes: true, attributeFilter: ["data-state"] });
  });
  let qid = null;
  for (let attempt = 1; attempt <= ATTEMPTS; attempt += 1) {
    qid = await nextQueryId(page, "evaluative", qid, 90_000);
    // Every state the page passes through from this answer on.
    await page.evaluate(() => {
      window.statesSeen = [];
    });
    spent = false;
    await page.keyboard.press("ArrowUp");
    await page.waitForSelector(`#history li[data-query-id="${qid}"]`, { timeout: 20_000 });
    if (refused.length > 0) break;
    console.log(`rate_limited: attempt ${attempt}: the answer to ${qid} went through unrefused (a starved server); trying the next query`);
  }

  check(refused.length >= 1 && refused.every((r) => r.id === qid && r.retry_after_ms > 0), `the answer was refused with a wait first: ${JSON.stringify(refused)}`);
  const mine = sent.filter((id) => id === qid).length;
  check(mine === refused.length + 1, `the page sent the answer again after each refusal: ${mine} sends, ${refused.length} refusals`);
  const states = await page.evaluate(() => window.statesSeen);
  check(!states.includes("query") || states.indexOf("query") > states.lastIndexOf("saving"), `the page never asked again while it waited: ${states}`);
  const answers = await api(`/api/sessions/${created.id}/answers`);
  const stored = answers.filter((x) => x.query_id === qid);
  check(stored.length === 1 && stored[0].value === 1, `the answer is stored once: ${JSON.stringify(stored)}`);
  await api(`/api/sessions/${created.id}/stop`, { method: "POST" });
  page.assertNoErrors();
});
