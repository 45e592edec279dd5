// The trainer's websocket (docs/protocol.md): reconnects by itself with backoff; on every
// (re)connection the server sends hello, progress and the pending query, so the page resumes
// where it was. Answers sent while the connection is down are kept and sent on reconnection
// (the server takes a repeated answer idempotently).

const MIN_DELAY_MS = 500;
const MAX_DELAY_MS = 8000;

export class TrainerSocket {
  /**
   * `url`: ws(s)://host/ws/sessions/{id}?token=...
   * `onMessage(msg)`: every server message. `onState(state, info)`: "connecting" | "connected" |
   * "reconnecting" (info.inMs) | "closed" (no more retries: the session ended or was refused).
   */
  constructor(url, { onMessage, onState }) {
    this.url = url;
    this.onMessage = onMessage;
    this.onState = onState;
    this.ws = null;
    this.attempt = 0;
    this.outbox = [];
    this.stopped = false;
    this.timer = null;
  }

  connect() {
    if (this.stopped) return;
    clearTimeout(this.timer);
    this.onState(this.attempt === 0 ? "connecting" : "reconnecting", { inMs: 0 });
    let ws;
    try {
      ws = new WebSocket(this.url);
    } catch (e) {
      this.scheduleRetry();
      return;
    }
    this.ws = ws;
    ws.addEventListener("open", () => {
      this.attempt = 0;
      this.onState("connected", {});
      const pending = this.outbox;
      this.outbox = [];
      for (const m of pending) this.send(m);
    });
    ws.addEventListener("message", (ev) => {
      let msg;
      try {
        msg = JSON.parse(ev.data);
      } catch {
        return; // The server only sends JSON; ignore anything else rather than crash.
      }
      if (msg.type === "ended") this.stopped = true;
      this.onMessage(msg);
    });
    ws.addEventListener("close", () => {
      if (this.ws !== ws) return;
      this.ws = null;
      if (this.stopped) {
        this.onState("closed", {});
        return;
      }
      this.scheduleRetry();
    });
    // "error" is always followed by "close"; the retry happens there.
  }

  scheduleRetry() {
    this.attempt += 1;
    const delay = Math.min(MAX_DELAY_MS, MIN_DELAY_MS * 2 ** (this.attempt - 1));
    const jittered = Math.round(delay * (0.8 + Math.random() * 0.4));
    this.onState("reconnecting", { inMs: jittered, attempt: this.attempt });
    this.timer = setTimeout(() => this.connect(), jittered);
  }

  /** Reconnect now (the "Retry now" button). */
  retryNow() {
    if (this.ws || this.stopped) return;
    this.connect();
  }

  get connected() {
    return this.ws !== null && this.ws.readyState === WebSocket.OPEN;
  }

  /** Send a message, or keep it for the next connection. */
  send(msg) {
    if (this.connected) this.ws.send(JSON.stringify(msg));
    else this.outbox.push(msg);
  }

  close() {
    this.stopped = true;
    clearTimeout(this.timer);
    if (this.ws) this.ws.close();
  }
}

/** The websocket URL for a session, from the page's own location. */
export function socketUrl(sessionId, token) {
  const scheme = location.protocol === "https:" ? "wss:" : "ws:";
  return `${scheme}//${location.host}/ws/sessions/${encodeURIComponent(sessionId)}?token=${encodeURIComponent(token)}`;
}
