"""The app in a real browser (headless Chromium through Selenium): upload a photo, move the light,
check the relit image, download it and compare it with the CLI's output for the same light."""

import io
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
import torch


def _wait(cond, timeout=120.0, what="condition"):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        v = cond()
        if v:
            return v
        time.sleep(0.2)
    raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")


def _img_src(drv, elem_id):
    from selenium.webdriver.common.by import By

    imgs = drv.find_elements(By.CSS_SELECTOR, f"#{elem_id} img")
    return imgs[0].get_attribute("src") if imgs and imgs[0].get_attribute("src") else None


def _fetch_png(url) -> np.ndarray:
    import PIL.Image

    with urllib.request.urlopen(url, timeout=30) as r:
        return np.asarray(PIL.Image.open(io.BytesIO(r.read())).convert("RGB")).astype(np.float64)


def _loaded(drv, elem_id):
    """The element's image is shown (its pixels are loaded), as a user sees it before clicking."""
    from selenium.webdriver.common.by import By

    imgs = drv.find_elements(By.CSS_SELECTOR, f"#{elem_id} img")
    return bool(imgs) and drv.execute_script("return arguments[0].complete && arguments[0].naturalWidth > 0;", imgs[0])


def _new_image(drv, elem_id, old, what):
    return _wait(lambda: (s := _img_src(drv, elem_id)) and s != old and s, what=what)


def _sides(img: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """Mean brightness of the person's left and right halves (split at the mask's centre column)."""
    ys, xs = np.nonzero(mask)
    mid = np.median(xs)
    lum = img.mean(-1)
    return float(lum[ys[xs < mid], xs[xs < mid]].mean()), float(lum[ys[xs > mid], xs[xs > mid]].mean())


@pytest.mark.slow
def test_relight_in_the_browser(running_app, browser, person_photo, tmp_path, monkeypatch):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    from relightnet.app.session import load_photo
    from relightnet.cli import main
    from relightnet.io import read_image
    from relightnet.light import load_light

    url, workdir = running_app
    assert url.startswith("http://127.0.0.1:")
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    drv = browser
    drv.get(url)
    upload = _wait(lambda: drv.find_elements(By.CSS_SELECTOR, "#photo-upload input[type=file]"), what="the page")
    upload[0].send_keys(str(person_photo))
    first = _new_image(drv, "relit", None, "the first relit image")
    assert _img_src(drv, "mask") and _img_src(drv, "original")
    mask = (load_photo(person_photo).mask > 0.5).numpy()

    # Point the light by clicking the sphere: on its left, then on its right (same height).
    def click_sphere(fx, fy, old):
        # click the sphere once its current image is on screen (a click while it loads has no pixel to point at)
        _wait(lambda: _loaded(drv, "light-sphere"), what="the sphere's image")
        sphere = drv.find_element(By.CSS_SELECTOR, "#light-sphere img")
        w = sphere.size["width"]
        dx, dy = int((fx - 0.5) * w), int((fy - 0.5) * w)  # offsets from the sphere's centre
        ActionChains(drv).move_to_element_with_offset(sphere, dx, dy).click().perform()
        return _new_image(drv, "relit", old, f"the relit image after a click at {fx:.2f}")

    left_src = click_sphere(0.1, 0.35, first)
    words_left = drv.find_element(By.CSS_SELECTOR, "#light-words textarea").get_attribute("value")
    left = _fetch_png(left_src)
    right_src = click_sphere(0.9, 0.35, left_src)
    right = _fetch_png(right_src)
    assert "az=-" in words_left  # a click on the left is a light from the image's left
    l_left, r_left = _sides(left, mask)
    l_right, r_right = _sides(right, mask)
    assert np.abs(left - right).max() > 20  # the relit image changed
    assert l_left > l_right and r_right > r_left  # the lit side is the brighter one
    assert l_left - r_left > 2 and r_right - l_right > 2
    # outside the person the photo is kept
    photo = read_image(person_photo).numpy() * 255
    np.testing.assert_allclose(left[~mask & (np.abs(left - right).max(-1) == 0)].mean(),
                               photo[~mask & (np.abs(left - right).max(-1) == 0)].mean(), atol=1)

    # Drag the azimuth slider: the image follows.
    knob = drv.find_element(By.CSS_SELECTOR, "#az input[type=range]")
    ActionChains(drv).click_and_hold(knob).move_by_offset(-knob.size["width"] // 4, 0).release().perform()
    dragged = _new_image(drv, "relit", right_src, "the relit image after dragging the azimuth")
    assert np.abs(_fetch_png(dragged) - right).max() > 5

    # Drag the light on the pad: pressed on the left, moved across, released on the right.
    pad = drv.find_element(By.CSS_SELECTOR, "#light-pad .light-pad")
    pw = pad.size["width"]
    before = _img_src(drv, "relit")
    ActionChains(drv).move_to_element_with_offset(pad, -pw // 3, -pw // 8).click_and_hold() \
        .move_by_offset(pw // 4, 0).move_by_offset(pw // 4, 0).move_by_offset(pw // 6, 0).release().perform()
    _wait(lambda: "az=" in (w := drv.find_element(By.CSS_SELECTOR, "#light-words textarea").get_attribute("value"))
          and not w.startswith("key:az=-"), what="a light from the right after the drag")
    dragged_pad = _fetch_png(_new_image(drv, "relit", before, "the relit image after the drag on the pad"))
    l_pad, r_pad = _sides(dragged_pad, mask)
    assert r_pad > l_pad  # now lit from the right

    # Download the relit photo and the light; compare with the CLI for the same light.
    words = drv.find_element(By.CSS_SELECTOR, "#light-words textarea").get_attribute("value")
    drv.find_element(By.CSS_SELECTOR, "#download-button").click()
    links = _wait(lambda: [a for a in drv.find_elements(By.CSS_SELECTOR, "#downloads a")
                           if (a.get_attribute("href") or "").endswith((".png", ".npz"))], what="the downloads")
    for a in links:
        a.click()
    def downloaded():
        got = {p.suffix: p for p in browser.download_dir.iterdir() if p.suffix in (".png", ".npz")}
        return got if len(got) == 2 and not list(browser.download_dir.glob("*.crdownload")) else None

    got = _wait(downloaded, what="the downloaded files")
    png, npz = got[".png"], got[".npz"]
    cli_out = tmp_path / "cli.png"
    assert main(["relight-image", str(person_photo), "--light", words, "--out", str(cli_out)]) == 0
    app_img, cli_img = read_image(png), read_image(cli_out)
    assert app_img.shape == cli_img.shape
    assert float((app_img - cli_img).abs().max()) <= 1.5 / 255  # float rounding of the same computation
    torch.testing.assert_close(load_light(npz), load_light(words))
    # Everything the app wrote is in its own folder.
    assert any(workdir.rglob("relit.png")) and list(cwd.iterdir()) == []


def test_video_tab_relights_into_the_apps_folder(predictor, person_photo, tmp_path):
    """The video tab's handler: relight-video on an uploaded clip, written in the app's folder."""
    from relightnet.app.ui import _Handlers
    from relightnet.io import VideoWriter, read_image, read_video

    frame = (read_image(person_photo).numpy() * 255).round().astype(np.uint8)
    clip = tmp_path / "clip.mkv"
    with VideoWriter(clip, fps=10) as v:
        for _ in range(3):
            v.write(frame)
    work = tmp_path / "app"
    work.mkdir()
    out = Path(_Handlers(work, predictor).run_video(str(clip), "key:az=-60,el=20,size=30,power=2", ""))
    assert out.is_relative_to(work) and out.suffix == ".mp4"
    frames = list(read_video(out))
    assert len(frames) == 3 and np.abs(frames[0].astype(float) - frame).max() > 10  # the person was relit


def test_a_click_on_the_sphere_points_the_light():
    """A click left of the sphere's centre is a light from the left; a click the browser sent without a
    pixel (the sphere's image still loading) leaves the sliders unchanged instead of failing."""
    import gradio as gr

    from relightnet.app.ui import SPHERE_SIZE, _pointed

    az, el, source = _pointed((SPHERE_SIZE // 10, SPHERE_SIZE // 2))
    assert az < -45 and abs(el) <= 1 and source == "direction"
    kept = _pointed(None)
    assert len(kept) == 3 and all(isinstance(v, type(gr.skip())) for v in kept)
