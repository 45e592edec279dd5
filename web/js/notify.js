// User-visible messages (errors, confirmations, offers such as "Undo"). Every failed request
// ends up here, so a page never fails silently or blank.

function container() {
  let box = document.getElementById("messages");
  if (!box) {
    box = document.createElement("div");
    box.id = "messages";
    document.body.append(box);
  }
  box.setAttribute("role", "status");
  box.setAttribute("aria-live", "polite");
  return box;
}

/**
 * Show a message. `kind`: "error" | "info" | "ok". Returns a handle with `close()`.
 * `action`: optional `{label, run}` shown as a button. `timeoutMs`: 0 keeps it until closed.
 */
export function notify(text, { kind = "info", timeoutMs = kind === "error" ? 8000 : 4000, action = null, key = null } = {}) {
  const box = container();
  if (key) {
    for (const old of box.querySelectorAll(`[data-key="${CSS.escape(key)}"]`)) old.remove();
  }
  const el = document.createElement("div");
  el.className = `message ${kind}`;
  if (key) el.dataset.key = key;
  const span = document.createElement("span");
  span.className = "text";
  span.textContent = text;
  el.append(span);
  let timer = null;
  const handle = {
    el,
    close() {
      clearTimeout(timer);
      el.remove();
    },
  };
  if (action) {
    const b = document.createElement("button");
    b.type = "button";
    b.textContent = action.label;
    b.addEventListener("click", () => {
      handle.close();
      action.run();
    });
    el.append(b);
  }
  const close = document.createElement("button");
  close.type = "button";
  close.setAttribute("aria-label", "Dismiss");
  close.textContent = "×";
  close.addEventListener("click", () => handle.close());
  el.append(close);
  box.append(el);
  if (timeoutMs > 0) timer = setTimeout(() => handle.close(), timeoutMs);
  return handle;
}

export function notifyError(err, context = "") {
  const text = err instanceof Error ? err.message : String(err);
  return notify(context ? `${context}: ${text}` : text, { kind: "error" });
}
