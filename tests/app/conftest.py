"""App-test fixtures: a generated photo of a person, the running app, a headless Chromium."""

import shutil

import pytest


@pytest.fixture(scope="session")
def person_photo(tmp_path_factory):
    """A 256² photo of a generated person over its background (the app's example person)."""
    from relightnet.app.examples import example_person

    return example_person(tmp_path_factory.mktemp("photo"))


@pytest.fixture(scope="module")
def predictor():
    """The shipped model as the jobs make it."""
    from relightnet.pipeline.backends import make_predictor

    return make_predictor()


@pytest.fixture(scope="module")
def running_app(predictor):
    """``(url, workdir)`` of the app served on 127.0.0.1 (a free port) for the module; stopped and its
    folder removed afterwards."""
    from relightnet.app.server import launch

    app, url, workdir = launch(0, predictor=predictor, block=False)
    try:
        yield url, workdir
    finally:
        app.close()
        shutil.rmtree(workdir, ignore_errors=True)


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    """Headless Chromium through Selenium (Debian's chromium and chromium-driver), downloads into a
    temporary folder (``browser.download_dir``)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    driver_path = shutil.which("chromedriver")
    if driver_path is None or shutil.which("chromium") is None:
        pytest.fail("the browser test needs Debian's chromium and chromium-driver (make system-deps)")
    dl = tmp_path_factory.mktemp("downloads")
    opts = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
              "--window-size=1400,2200", "--disable-extensions"):
        opts.add_argument(a)
    opts.binary_location = shutil.which("chromium")
    opts.add_experimental_option("prefs", {"download.default_directory": str(dl),
                                           "download.prompt_for_download": False})
    drv = webdriver.Chrome(service=Service(driver_path), options=opts)
    drv.download_dir = dl
    try:
        yield drv
    finally:
        drv.quit()
