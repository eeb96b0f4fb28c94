"""Batch planning: a dataset of plans (objects × conditions × seeds × hands, each optionally
validated in Drake) run as Ray tasks on one machine or a cluster, the rows streamed to Parquet.

    from eos_svc.batch import load_spec, expand
    spec = load_spec("docs/batch-example.toml")   # BatchSpec (checked; ValidationError names the field)
    keys = expand(spec)                           # PlanKey per plan, stable ids

    from eos_svc.batch.runner import run_batch    # needs the batch extra (Ray, pyarrow)
    summary = run_batch(spec, "out/")             # resumes what out/ holds

    from eos_svc.batch.store import read_rows
    table = read_rows("out/")                     # a pyarrow Table of every committed row

This package's top level imports neither Ray nor pyarrow; :mod:`~eos_svc.batch.runner` and
:mod:`~eos_svc.batch.store` do. See ``docs/batch.md``.
"""

from eos_svc.batch.expansion import PlanKey, expand, plan_id
from eos_svc.batch.spec import BatchSpec, load_spec, spec_from_dict

__all__ = ["BatchSpec", "PlanKey", "expand", "load_spec", "plan_id", "spec_from_dict"]
