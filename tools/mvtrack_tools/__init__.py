"""mvtrack's Python tools: simulate scenes, replay logs, evaluate, plot."""
