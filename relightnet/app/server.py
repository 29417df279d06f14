"""Start the app on 127.0.0.1 with its own temporary folder, and remove the folder when it stops."""

from __future__ import annotations

import logging
import os
import shutil
import tempfile
from pathlib import Path

__all__ = ["HOST", "app_workdir", "launch"]

logger = logging.getLogger("relightnet.app")

#: The only address the app listens on.
HOST = "127.0.0.1"


def app_workdir() -> Path:
    """A fresh temporary folder for one run of the app; Gradio's uploads and cache go in it too
    (``GRADIO_TEMP_DIR``, set before Gradio is imported)."""
    d = Path(tempfile.mkdtemp(prefix="relightnet-app-"))
    os.environ["GRADIO_TEMP_DIR"] = str(d / "gradio")
    os.environ.setdefault("GRADIO_ANALYTICS_ENABLED", "False")
    return d


def launch(port: int = 7860, predictor=None, block: bool = True, workdir: Path | None = None):
    """Build and start the app (:func:`relightnet.app.ui.build_app`) on ``127.0.0.1:port``.

    Args:
        port: TCP port (0: any free one).
        predictor: the CNN (default: the shipped model).
        block: serve until interrupted (Ctrl-C or SIGTERM), then remove the temporary folder;
            False returns at once.
        workdir: the app's folder (default: :func:`app_workdir`).

    Returns:
        ``(app, url, workdir)`` when ``block`` is False (call ``app.close()`` and remove ``workdir``).
    """
    workdir = app_workdir() if workdir is None else Path(workdir)
    from .ui import build_app

    app = build_app(workdir, predictor)
    try:
        _, url, _ = app.queue().launch(server_name=HOST, server_port=port or None, share=False, quiet=True,
                                       prevent_thread_lock=True, allowed_paths=[str(workdir)],
                                       footer_links=[], show_error=True)
        logger.info("relightnet app on %s (temporary files in %s); Ctrl-C stops it", url, workdir)
        if not block:
            return app, url, workdir
        import signal

        def stop(signum, frame):  # `kill` stops it like Ctrl-C: the folder is removed
            raise KeyboardInterrupt

        signal.signal(signal.SIGTERM, stop)
        app.block_thread()
    finally:
        if block:
            app.close()
            shutil.rmtree(workdir, ignore_errors=True)
    return None
