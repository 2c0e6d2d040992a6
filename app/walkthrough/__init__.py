"""The Walkthrough tab: CBM's steps one by one on the frame on screen (``steps``: plain data;
``panel``: the tab and its scene nodes)."""
