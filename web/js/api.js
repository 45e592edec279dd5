// The REST API: fetch with the researcher token, JSON in and out, and errors turned into
// readable messages (the server's `{"error": {"code", "message"}}` shape).

const TOKEN_KEY = "dualrep.token";

export function getToken() {
  return localStorage.getItem(TOKEN_KEY) || "";
}

export function setToken(token) {
  if (token) localStorage.setItem(TOKEN_KEY, token);
  else localStorage.removeItem(TOKEN_KEY);
}

export class ApiError extends Error {
  constructor(status, code, message) {
    super(message);
    this.status = status;
    this.code = code;
  }
}

async function errorFrom(res) {
  let code = `http_${res.status}`;
  let message = `${res.status} ${res.statusText}`;
  try {
    const body = await res.json();
    if (body && body.error) {
      code = body.error.code || code;
      message = body.error.message || message;
    }
  } catch {
    // Not JSON: keep the status line.
  }
  if (res.status === 401) message = `Not signed in: ${message}. Enter the researcher token.`;
  return new ApiError(res.status, code, message);
}

/** `fetch` with the token. Throws `ApiError` on a refusal and on a network failure. */
export async function request(path, { method = "GET", body, token = getToken(), accept = "application/json" } = {}) {
  const headers = { Accept: accept };
  if (token) headers.Authorization = `Bearer ${token}`;
  if (body !== undefined) headers["Content-Type"] = "application/json";
  let res;
  try {
    res = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  } catch (e) {
    throw new ApiError(0, "network", `The server cannot be reached (${e.message}).`);
  }
  if (!res.ok) throw await errorFrom(res);
  return res;
}

export async function getJson(path, opts) {
  return (await request(path, opts)).json();
}

export async function postJson(path, body, opts = {}) {
  const res = await request(path, { ...opts, method: "POST", body });
  const text = await res.text();
  return text ? JSON.parse(text) : null;
}

/** Download an authenticated file (export, recording) through a temporary link. */
export async function download(path, filename) {
  const res = await request(path, { accept: "*/*" });
  const blob = await res.blob();
  const url = URL.createObjectURL(blob);
  const a = document.createElement("a");
  a.href = url;
  a.download = filename;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10_000);
}
