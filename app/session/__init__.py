"""A tab's state and computation, free of any GUI: its settings (``settings``), what every tab
shares and what one recompute produces (``explorer``), recompute coalescing and long tasks
(``coalesce``, ``background``), presets on disk, sequence runs, parameter search, worst frames and
exports. Nothing here imports viser or the other parts of ``app``."""
