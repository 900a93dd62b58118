"""Observer gains: deadbeat, pole placement, pseudo-inverse and online gradient, verified."""
