"""A number box given text says so. viser's number boxes (a slider's and ``add_number``'s) take
digits only: letters typed are dropped in the browser, the box goes blank, and the server never
hears of it. So each page runs a small script of its own: a letter typed (or pasted) into a number
box shows a note under the box ("'abc' is not a number; the value stays 3"), and a box left blank
gets its value back. The note is set as text, never as markup."""
from __future__ import annotations

import viser
from viser._messages import RunJavascriptMessage

NOTE_ID = "cbm-number-note"
SCRIPT = """
(() => {
  if (window.cbmNumberBoxes) return;
  window.cbmNumberBoxes = true;
  const isBox = (t) => t instanceof HTMLInputElement && t.classList.contains("mantine-NumberInput-input");
  const setValue = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, "value").set;
  const say = (box, text) => {
    let note = document.getElementById("NOTE_ID_HERE");
    if (!note) {
      note = document.createElement("div");
      note.id = "NOTE_ID_HERE";
      note.setAttribute("role", "status");
      note.style.cssText = "position:fixed;z-index:1000;max-width:260px;font:12px/1.3 system-ui,sans-serif;" +
        "background:#fff3bf;color:#5c3c00;border:1px solid #e8c15a;border-radius:4px;padding:2px 6px;" +
        "pointer-events:none";
      document.body.appendChild(note);
    }
    const r = box.getBoundingClientRect();
    note.textContent = text;
    note.style.display = "block";
    note.style.top = (r.bottom + 2) + "px";
    note.style.left = Math.max(4, Math.min(r.left, window.innerWidth - 268)) + "px";
    clearTimeout(note.hideLater);
    note.hideLater = setTimeout(() => { note.style.display = "none"; }, 5000);
  };
  document.addEventListener("focusin", (e) => {
    if (isBox(e.target)) { e.target.dataset.cbmKept = e.target.value; e.target.dataset.cbmTyped = ""; }
  }, true);
  document.addEventListener("beforeinput", (e) => {
    const box = e.target;
    const text = e.data || (e.dataTransfer && e.dataTransfer.getData("text")) || "";
    if (!isBox(box) || !/[^0-9.,eE+\\-\\s]/.test(text)) return;
    box.dataset.cbmTyped = (box.dataset.cbmTyped || "") + text;
    say(box, "'" + box.dataset.cbmTyped + "' is not a number; the value stays " + box.dataset.cbmKept + ".");
  }, true);
  document.addEventListener("focusout", (e) => {
    const box = e.target;
    if (!isBox(box) || box.value.trim() !== "" || !box.dataset.cbmKept) return;
    setValue.call(box, box.dataset.cbmKept);
    box.dispatchEvent(new Event("input", { bubbles: true }));
  }, true);
})();
""".replace("NOTE_ID_HERE", NOTE_ID)
"""The page's script (runs once per page, whatever calls it)."""


def teach(client: viser.ClientHandle) -> None:
    """Have the page of ``client`` say when a number box is given text (``SCRIPT``)."""
    client._websock_connection.queue_message(RunJavascriptMessage(source=SCRIPT))
