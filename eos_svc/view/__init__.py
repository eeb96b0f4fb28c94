"""3-D views of a plan in the browser with Drake's MeshCat: one self-contained HTML file
(:func:`write_result_html`, :func:`write_plan_html`) or a live page (:class:`LiveView`); ``docs/view.md``.
"""

from eos_svc.view.replay_html import plan_page, write_plan_html, write_result_html

__all__ = ["plan_page", "write_plan_html", "write_result_html"]
