//! The page around the canvas: URL parameters, the status line and result block the browser test reads,
//! the scene menu, the file picker and drag and drop, downloads.

use std::cell::RefCell;
use std::rc::Rc;

use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::Closure;

/// What the page's URL asks for: `?scene=NAME` (a bundled scene), `&script=NAME` (a bundled script to
/// play), `&source=TEXT` (a scene's text, as a dropped file would give), `&educator` (the material and
/// simulation panels, as the native `--educator`).
#[derive(Clone, Debug, Default)]
pub struct Params {
    /// A bundled scene's name (`durotomy`, `meninges`), or none for the default.
    pub scene: Option<String>,
    /// A bundled script's name (`meninges_careful`).
    pub script: Option<String>,
    /// A scene's text given in the URL.
    pub source: Option<String>,
    /// Educator mode.
    pub educator: bool,
}

impl Params {
    /// The current page's parameters.
    pub fn from_url() -> Self {
        let search = web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default();
        let Ok(p) = web_sys::UrlSearchParams::new_with_str(&search) else { return Self::default() };
        let get = |k: &str| p.get(k).filter(|s| !s.is_empty());
        Self {
            scene: get("scene"),
            script: get("script"),
            source: get("source"),
            educator: p.has("educator"),
        }
    }
}

fn document() -> Option<web_sys::Document> {
    web_sys::window()?.document()
}

fn element(id: &str) -> Option<web_sys::Element> {
    document()?.get_element_by_id(id)
}

/// Sets the text of the element `id` (no-op if the page lacks it).
pub fn set_text(id: &str, text: &str) {
    if let Some(e) = element(id) {
        e.set_text_content(Some(text));
    }
}

/// Shows an error in the page's error box (and the console).
pub fn show_error(text: &str) {
    web_sys::console::error_1(&text.into());
    if let Some(e) = element("error") {
        e.set_text_content(Some(text));
        let _ = e.set_attribute("class", "shown");
    }
}

/// Hides the error box.
pub fn clear_error() {
    if let Some(e) = element("error") {
        e.set_text_content(None);
        let _ = e.set_attribute("class", "");
    }
}

/// Writes `text` into the `<pre id="result">` the browser test reads, and marks the page done.
pub fn set_result(text: &str) {
    set_text("result", text);
    if let Some(b) = document().and_then(|d| d.body()) {
        let _ = b.set_attribute("data-done", "1");
    }
}

/// Marks that the first frame has been drawn (`<body data-first-frame="MS">`, milliseconds since
/// navigation).
pub fn mark_first_frame(ms: f64) {
    if let Some(b) = document().and_then(|d| d.body()) {
        let _ = b.set_attribute("data-first-frame", &format!("{ms:.0}"));
    }
}

/// Publishes the views' areas (`<body data-views="[[x, y, w, h], ...]">`, CSS pixels of the page) from
/// their areas in the canvas's physical pixels.
pub fn set_views(rects: &[[f32; 4]]) {
    let Some(w) = web_sys::window() else { return };
    let dpr = w.device_pixel_ratio() as f32;
    let Some(canvas) = element("dissect") else { return };
    let b = canvas.get_bounding_client_rect();
    let (ox, oy) = (b.left() as f32, b.top() as f32);
    let list: Vec<String> = rects
        .iter()
        .map(|r| {
            format!("[{:.0},{:.0},{:.0},{:.0}]", ox + r[0] / dpr, oy + r[1] / dpr, r[2] / dpr, r[3] / dpr)
        })
        .collect();
    if let Some(body) = document().and_then(|d| d.body()) {
        let _ = body.set_attribute("data-views", &format!("[{}]", list.join(",")));
    }
}

/// Publishes what the trainee's hand is doing (`<body data-live="{...}">`: the instrument, whether it
/// holds tissue, elements moved and links cut so far), for the browser test that drives the mouse.
pub fn set_live(json: &str) {
    if let Some(body) = document().and_then(|d| d.body()) {
        let _ = body.set_attribute("data-live", json);
    }
}

/// Milliseconds since navigation.
pub fn now_ms() -> f64 {
    web_sys::window().and_then(|w| w.performance()).map(|p| p.now()).unwrap_or(0.0)
}

/// Offers `bytes` as a download named `name`.
pub fn download(name: &str, mime: &str, bytes: &[u8]) -> Result<(), String> {
    let err = |e: wasm_bindgen::JsValue| format!("download failed: {e:?}");
    let array = js_sys::Uint8Array::from(bytes);
    let parts = js_sys::Array::of1(&array);
    let options = web_sys::BlobPropertyBag::new();
    options.set_type(mime);
    let blob = web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &options).map_err(err)?;
    let url = web_sys::Url::create_object_url_with_blob(&blob).map_err(err)?;
    let doc = document().ok_or("no document")?;
    let a: web_sys::HtmlAnchorElement =
        doc.create_element("a").map_err(err)?.dyn_into().map_err(|_| "not an anchor".to_string())?;
    a.set_href(&url);
    a.set_download(name);
    a.click();
    let _ = web_sys::Url::revoke_object_url(&url);
    Ok(())
}

/// What the page asks the app to do (filled by DOM callbacks, drained each frame).
#[derive(Debug)]
pub enum Request {
    /// Open a bundled scene by name.
    Bundled(String),
    /// Open a scene file's text (picked or dropped), with its name.
    File { name: String, text: String },
    /// Download the session's recording.
    DownloadRecording,
    /// Download the session's report.
    DownloadReport,
}

/// The queue the page's callbacks fill.
pub type Requests = Rc<RefCell<Vec<Request>>>;

fn read_file(file: web_sys::File, requests: Requests) {
    let name = file.name();
    wasm_bindgen_futures::spawn_local(async move {
        match wasm_bindgen_futures::JsFuture::from(file.text()).await {
            Ok(text) => {
                requests.borrow_mut().push(Request::File { name, text: text.as_string().unwrap_or_default() })
            }
            Err(e) => show_error(&format!("{name}: cannot read the file: {e:?}")),
        }
    });
}

fn on<E: wasm_bindgen::convert::FromWasmAbi + 'static>(
    target: &web_sys::EventTarget,
    event: &str,
    f: impl FnMut(E) + 'static,
) {
    let closure = Closure::<dyn FnMut(E)>::new(f);
    let _ = target.add_event_listener_with_callback(event, closure.as_ref().unchecked_ref());
    closure.forget();
}

/// Fills the scene menu with `scenes` and wires the menu, the file picker, drag and drop and the
/// download buttons to `requests`.
pub fn wire(scenes: &[&str], current: &str, requests: &Requests) {
    let Some(doc) = document() else { return };
    if let Some(menu) = element("scenes").and_then(|e| e.dyn_into::<web_sys::HtmlSelectElement>().ok()) {
        for name in scenes {
            if let Ok(o) = doc.create_element("option") {
                let _ = o.set_attribute("value", name);
                o.set_text_content(Some(name));
                if *name == current {
                    let _ = o.set_attribute("selected", "");
                }
                let _ = menu.append_child(&o);
            }
        }
        let r = requests.clone();
        let m = menu.clone();
        on(&menu, "change", move |_: web_sys::Event| r.borrow_mut().push(Request::Bundled(m.value())));
    }
    if let Some(input) = element("file").and_then(|e| e.dyn_into::<web_sys::HtmlInputElement>().ok()) {
        let r = requests.clone();
        let i = input.clone();
        on(&input, "change", move |_: web_sys::Event| {
            if let Some(f) = i.files().and_then(|l| l.get(0)) {
                read_file(f, r.clone());
            }
            i.set_value("");
        });
    }
    if let Some(body) = doc.body() {
        on(&body, "dragover", |e: web_sys::DragEvent| e.prevent_default());
        let r = requests.clone();
        on(&body, "drop", move |e: web_sys::DragEvent| {
            e.prevent_default();
            if let Some(f) = e.data_transfer().and_then(|d| d.files()).and_then(|l| l.get(0)) {
                read_file(f, r.clone());
            }
        });
    }
    for (id, what) in [("get-recording", 0), ("get-report", 1)] {
        if let Some(b) = element(id) {
            let r = requests.clone();
            on(&b, "click", move |_: web_sys::Event| {
                r.borrow_mut().push(if what == 0 {
                    Request::DownloadRecording
                } else {
                    Request::DownloadReport
                })
            });
        }
    }
}
