"""Reports people look at: plots (matplotlib, optional extra ``plot``)."""
