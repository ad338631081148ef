// Downloads: a text saved as a file, the file names (from the bicycle's
// name) and the eigenvalue table as CSV. The buttons are wired in
// explorer.js; the figures come from their panels.
// Shares the page's state through `Explorer` (explorer.js).
(function (app) {
  "use strict";
  const S = ExplorerState;
  const { call, showError, bicycleSpec, withModel } = app;

  // ---- downloads ---------------------------------------------------------------

  function download(name, text, type) {
    const blob = new Blob([text], { type });
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = name;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 2000);
  }
  const slug = () => (app.current ? app.current.name : "bicycle").replace(/[^A-Za-z0-9_.-]+/g, "_").replace(/^_+|_+$/g, "") || "bicycle";

  /** The eigenvalue table exactly as `bikedyn eig --format csv` writes it. */
  function eigCsv() {
    const r = call(withModel({ job: "eig", bicycle: bicycleSpec(), speeds: S.speedRange(app.state), csv: true }));
    if (r.error) {
      showError(r.error);
      return null;
    }
    return r.ok.csv;
  }

  // Used by the other files.
  Object.assign(app, { download, slug, eigCsv });
})(window.Explorer);
