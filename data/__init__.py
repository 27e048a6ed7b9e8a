"""The benchmark data (one folder per domain, LLM+P layout), installed as the package
``twostep.data``: the default ``data.root`` (``twostep.tasks.benchmark.DEFAULT_DATA_ROOT``)."""
