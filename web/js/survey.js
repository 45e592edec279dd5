// The three questions at the end of a trainer's session (1 to 5 each): the scales built from
// the page's fieldsets, and the answers posted to the session's survey with the trainer's
// token (a getter: naming oneself on a shared link changes the token mid-page).

import { postJson } from "./api.js";
import { notify } from "./notify.js";

const $ = (id) => document.getElementById(id);

export function buildSurvey({ sessionId, token, onSaved }) {
  for (const fs of document.querySelectorAll("#survey fieldset")) {
    const scale = fs.querySelector(".scale");
    const name = fs.dataset.name;
    const low = Object.assign(document.createElement("span"), { className: "end", textContent: scale.dataset.low });
    const high = Object.assign(document.createElement("span"), { className: "end", textContent: scale.dataset.high });
    scale.append(low);
    for (let v = 1; v <= 5; v += 1) {
      const label = document.createElement("label");
      const input = Object.assign(document.createElement("input"), { type: "radio", name, value: String(v), required: true });
      label.append(input, String(v));
      scale.append(label);
    }
    scale.append(high);
  }
  $("survey-form").addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const data = new FormData(ev.target);
    const body = {};
    for (const fs of document.querySelectorAll("#survey fieldset")) body[fs.dataset.name] = Number(data.get(fs.dataset.name));
    const result = $("survey-result");
    result.textContent = "Sending…";
    try {
      await postJson(`/api/sessions/${encodeURIComponent(sessionId)}/survey`, body, { token: token() });
      result.textContent = "Saved. Thank you for teaching the robot!";
      ev.target.querySelector("button[type=submit]").disabled = true;
      onSaved();
    } catch (e) {
      result.textContent = `Your answers could not be saved: ${e.message}`;
      notify(`Your answers could not be saved: ${e.message}`, { kind: "error" });
    }
  });
}
