"""Mission -> optimised reference: mission, collocation program, solve, result, compare, min-time."""
