"""3-D views of a plan in the browser, with Drake's MeshCat.

- :func:`write_result_html` / :func:`write_plan_html`: one self-contained HTML file animating
  a whole plan (``eos plan --html FILE``, ``eos replay REC --html FILE``);
- :class:`LiveView`: a MeshCat page served on localhost that follows a plan's cycles as they
  happen (``eos plan --view``, ``eos client watch --view``).

Why Drake's MeshCat, what is drawn and how the pages are tested: ``docs/view.md``.
"""

from eos_svc.view.replay_html import plan_page, write_plan_html, write_result_html

__all__ = ["plan_page", "write_plan_html", "write_result_html"]
