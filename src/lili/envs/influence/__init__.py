"""Small repeated-interaction envs whose best greedy and influencing policies are known."""
