"""Play against a trained agent in a browser (``lili play air-hockey``), or let a bot play.

- :mod:`lili.play.striker`: a person's aim as the env's striker, and the human-like bot.
- :mod:`lili.play.policy`: the one adapter to the agent API (acting, latent updates).
- :mod:`lili.play.session`: one game on the MuJoCo table; :mod:`lili.play.record`: its CSV.
- :mod:`lili.play.probe`: what the blocker believes (the next mode read off its latent).
- :mod:`lili.play.protocol`, :mod:`lili.play.server`: the validated WebSocket game and the page.
- :mod:`lili.play.bot`: headless games against the bot; :mod:`lili.play.ship`: trains the
  shipped agent; :mod:`lili.play.command`: the ``lili play`` command line.
"""
