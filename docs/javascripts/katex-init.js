// Typesets the mathematics of the site with the KaTeX served from docs/assets/katex/.
// pymdownx.arithmatex (generic mode, mkdocs.yml) leaves each formula as TeX in an element of
// class "arithmatex": <span> for inline math, wrapped in \( \), and <div> for display math,
// wrapped in \[ \] (an \begin{...} environment is left unwrapped). Each one is replaced by
// KaTeX's HTML; a formula KaTeX cannot parse is shown as its source in red, not dropped.
(function () {
  "use strict";

  function unwrap(tex) {
    var open = tex.slice(0, 2);
    if ((open === "\\(" && tex.slice(-2) === "\\)") || (open === "\\[" && tex.slice(-2) === "\\]")) {
      return tex.slice(2, -2);
    }
    return tex;
  }

  function typeset() {
    var nodes = document.querySelectorAll(".arithmatex");
    for (var i = 0; i < nodes.length; i++) {
      var node = nodes[i];
      katex.render(unwrap(node.textContent.trim()), node, {
        displayMode: node.tagName === "DIV",
        throwOnError: false,
      });
    }
  }

  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", typeset);
  } else {
    typeset();
  }
})();
