"""What an outcome looks like: plain arrays and text (``drawing``, ``layouts``, ``picking``,
``text``, ``inspector``, ``colours``, ``geometry``), and the one module that puts them into a
browser tab's 3D scene (``view``)."""
