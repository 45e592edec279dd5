// Shared by the browser tests: Debian's Chromium through playwright-core, a page that fails the
// test on any console error or page error, screenshots into the artifacts folder, and the REST
// API with the researcher token. Run by tests/browser.rs, which starts the real server.

import { mkdirSync } from "node:fs";
import { join } from "node:path";
import { chromium } from "playwright-core";

export const BASE = need("DUALREP_URL");
export const TOKEN = need("DUALREP_TOKEN");
export const ARTIFACTS = process.env.DUALREP_ARTIFACTS || "target/browser-artifacts";
mkdirSync(ARTIFACTS, { recursive: true });

function need(name) {
  const v = process.env[name];
  if (!v) {
    console.error(`${name} is not set: run these scripts through \`cargo test --test suite browser::\``);
    process.exit(2);
  }
  return v;
}

export function check(cond, message) {
  if (!cond) throw new Error(`check failed: ${message}`);
}

export async function launch() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
    headless: true,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking"],
  });
}

/** A page whose console errors and uncaught exceptions are collected; `done()` asserts none. */
export async function newPage(browser, { width = 1280, height = 800, token = TOKEN } = {}) {
  const context = await browser.newContext({ viewport: { width, height }, baseURL: BASE });
  if (token) {
    await context.addInitScript((t) => localStorage.setItem("dualrep.token", t), token);
  }
  const page = await context.newPage();
  const errors = [];
  page.on("console", (m) => {
    if (m.type() === "error") errors.push(`console.error: ${m.text()} (${m.location().url})`);
  });
  page.on("pageerror", (e) => errors.push(`page error: ${e.message}`));
  page.errors = errors;
  page.assertNoErrors = () => check(errors.length === 0, `the page logged errors:\n${errors.join("\n")}`);
  return page;
}

export async function shot(page, name) {
  const path = join(ARTIFACTS, `${name}.png`);
  await page.screenshot({ path, fullPage: true });
  console.log(`screenshot: ${path}`);
  return path;
}

export async function api(path, { method = "GET", body } = {}) {
  const res = await fetch(new URL(path, BASE), {
    method,
    headers: { Authorization: `Bearer ${TOKEN}`, ...(body ? { "Content-Type": "application/json" } : {}) },
    body: body ? JSON.stringify(body) : undefined,
  });
  const text = await res.text();
  if (!res.ok) throw new Error(`${method} ${path}: ${res.status} ${text}`);
  return text ? JSON.parse(text) : null;
}

export async function waitFor(what, fn, { timeoutMs = 60_000, everyMs = 250 } = {}) {
  const until = Date.now() + timeoutMs;
  let last;
  while (Date.now() < until) {
    last = await fn();
    if (last) return last;
    await new Promise((r) => setTimeout(r, everyMs));
  }
  throw new Error(`timed out after ${timeoutMs} ms waiting for ${what} (last: ${JSON.stringify(last)})`);
}

/** The id of the query on screen, once one is (a different one from `notId`). */
export async function nextQueryId(page, kind, notId = null, timeoutMs = 60_000) {
  const sel = kind === "evaluative" ? "#evaluative" : "#preference";
  const handle = await page.waitForFunction(
    ([s, not]) => {
      const el = document.querySelector(s);
      const id = el?.dataset.queryId;
      return id && !el.classList.contains("hidden") && id !== not && document.body.dataset.state === "query" ? id : null;
    },
    [sel, notId === null ? null : String(notId)],
    { timeout: timeoutMs },
  );
  return Number(await handle.jsonValue());
}

/** Runs `body(browser)`, closing the browser whatever happens; exits 1 on failure. */
export async function run(name, body) {
  const browser = await launch();
  try {
    await body(browser);
    console.log(`${name}: ok`);
  } catch (e) {
    console.error(`${name}: FAILED\n${e.stack || e}`);
    process.exitCode = 1;
  } finally {
    await browser.close();
  }
}
