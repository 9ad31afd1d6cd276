//! The real `studio` binary, attacked and stopped as `SECURITY.md` says: its temporary folder
//! (mode 0700, removed on SIGTERM as on Ctrl-C), a stop while an upload is unfinished or a
//! trainer tab has stopped reading, a second Ctrl-C, and a compressed VTU bomb uploaded as an
//! organ with the server's peak memory read from `/proc`. A binary of its own: each test starts
//! its own server process with its own `TMPDIR`.
#![cfg(unix)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

/// A studio process with its own temporary directory.
struct Server {
    child: Child,
    addr: SocketAddr,
    tmp: PathBuf,
}

impl Server {
    fn start(name: &str) -> Result<Server> {
        let tmp = std::env::temp_dir().join(format!("studio-test-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir_all(&tmp)?;
        Server::start_in(tmp, &[])
    }

    /// A studio with `TMPDIR` `tmp` (made already) and its case library in `tmp/data` (never
    /// the user's), with `args` besides.
    fn start_in(tmp: PathBuf, args: &[&str]) -> Result<Server> {
        let data = tmp.join("data");
        let mut child = Command::new(env!("CARGO_BIN_EXE_studio"))
            .args(["--port", "0", "--data"])
            .arg(&data)
            .args(args)
            .env("TMPDIR", &tmp)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()?;
        let stdout = child.stdout.take().ok_or("no stdout")?;
        let mut line = String::new();
        BufReader::new(stdout).read_line(&mut line)?;
        let addr = line
            .trim()
            .strip_prefix("studio: http://")
            .and_then(|s| s.strip_suffix('/'))
            .ok_or_else(|| format!("not an address line: {line:?}"))?
            .parse()?;
        Ok(Server { child, addr, tmp })
    }

    fn pid(&self) -> String {
        self.child.id().to_string()
    }

    /// The server's own folder in `TMPDIR` (`tissue-studio-…`), if it exists.
    fn folders(&self) -> Result<Vec<PathBuf>> {
        Ok(std::fs::read_dir(&self.tmp)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with("tissue-studio-"))
            })
            .collect())
    }

    fn signal(&self, name: &str) -> Result {
        let status = Command::new("kill")
            .args([&format!("-{name}"), &self.pid()])
            .status()?;
        assert!(status.success(), "kill -{name}");
        Ok(())
    }

    /// Waits up to `limit` for the exit; its code and how long it took.
    fn wait_exit(&mut self, limit: Duration) -> Result<(Option<i32>, Duration)> {
        let t0 = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait()? {
                return Ok((status.code(), t0.elapsed()));
            }
            if t0.elapsed() > limit {
                let _ = self.child.kill();
                return Err(format!("studio did not exit within {limit:?}").into());
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// A proc/PID/status field in kB.
    fn status_kb(&self, field: &str) -> Result<u64> {
        let text = std::fs::read_to_string(format!("/proc/{}/status", self.child.id()))?;
        text.lines()
            .find_map(|l| l.strip_prefix(field))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
            .ok_or_else(|| format!("no {field} in /proc/PID/status").into())
    }

    /// An upload that declares 60 MB, sends a line and then nothing: the connection held open,
    /// once the server has read its headers.
    fn hold_upload(&self) -> Result<TcpStream> {
        let mut held = TcpStream::connect(self.addr)?;
        write!(
            held,
            "POST /api/patients?name=a.obj&unit=cm HTTP/1.1\r\nHost: {}\r\nContent-Type: \
             application/octet-stream\r\nContent-Length: 60000000\r\n\r\nv 0 0 0\n",
            self.addr
        )?;
        std::thread::sleep(Duration::from_millis(300));
        Ok(held)
    }

    /// An HTTP/1.1 request with `Connection: close`; the status and the body.
    fn request(
        &self,
        method: &str,
        path: &str,
        headers: &str,
        body: &[u8],
    ) -> Result<(u16, String)> {
        let mut s = TcpStream::connect(self.addr)?;
        s.set_read_timeout(Some(Duration::from_secs(120)))?;
        write!(
            s,
            "{method} {path} HTTP/1.1\r\nHost: {}\r\n{headers}Content-Length: {}\r\nConnection: close\r\n\r\n",
            self.addr,
            body.len()
        )?;
        s.write_all(body)?;
        let mut got = Vec::new();
        s.read_to_end(&mut got)?;
        let text = String::from_utf8_lossy(&got).into_owned();
        let status = text
            .split_whitespace()
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or(0);
        let body = text
            .split_once("\r\n\r\n")
            .map_or("", |(_, b)| b)
            .to_owned();
        Ok((status, body))
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.tmp);
    }
}

/// Runs a 5-step job on `patient` over the job socket; its id once finished.
fn run_short_job(addr: SocketAddr, patient: &serde_json::Value) -> Result<String> {
    use futures_util::{SinkExt, StreamExt};
    use tokio_tungstenite::tungstenite::Message;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    rt.block_on(async {
        let (mut tab, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/ws")).await?;
        let run = serde_json::json!({ "type": "run", "patient": patient,
                                      "request": { "max_steps": 5 } });
        tab.send(Message::Text(run.to_string().into())).await?;
        loop {
            let m = tokio::time::timeout(Duration::from_secs(120), tab.next())
                .await?
                .ok_or("the socket closed")??;
            let Message::Text(t) = m else { continue };
            let v: serde_json::Value = serde_json::from_str(&t)?;
            match v["type"].as_str() {
                Some("finished") => return Ok(v["job"].as_str().unwrap_or("").to_owned()),
                Some("failed" | "refused" | "cancelled") => return Err(format!("{v}").into()),
                _ => {}
            }
        }
    })
}

fn mode(p: &Path) -> Result<u32> {
    Ok(std::fs::metadata(p)?.permissions().mode() & 0o777)
}

#[test]
fn sigterm_cleans_up_like_ctrl_c_and_the_folder_is_private() -> Result {
    let mut server = Server::start("term")?;
    let folders = server.folders()?;
    assert_eq!(folders.len(), 1, "{folders:?}");
    let folder = &folders[0];
    assert_eq!(mode(folder)?, 0o700, "other users cannot list or read it");
    // A patient and a finished job leave the patient's files in it.
    let (status, body) = server.request("POST", "/api/patients?shipped=table2", "", b"")?;
    assert_eq!(status, 200, "{body}");
    let patient: serde_json::Value = serde_json::from_str(&body)?;
    let job = run_short_job(server.addr, &patient["patient"])?;
    let files = std::fs::read_dir(folder.join(&job))?.count();
    assert!(files >= 4, "{files} files of job {job}");
    server.signal("TERM")?;
    let (code, took) = server.wait_exit(Duration::from_secs(10))?;
    assert_eq!(code, Some(0), "SIGTERM is a clean stop");
    assert!(!folder.exists(), "the patient's folder is removed");
    eprintln!("SIGTERM to exit: {took:?}");
    Ok(())
}

#[test]
fn a_stop_ends_while_an_upload_is_unfinished_and_a_second_ctrl_c_forces_it() -> Result {
    // One Ctrl-C: the held upload is given the grace (3 s), then the process exits anyway.
    let mut server = Server::start("int")?;
    let folder = server.folders()?.remove(0);
    let held = server.hold_upload()?;
    server.signal("INT")?;
    let (code, took) = server.wait_exit(Duration::from_secs(10))?;
    assert_eq!(code, Some(0));
    assert!(took < Duration::from_secs(6), "exit took {took:?}");
    assert!(!folder.exists());
    drop(held);

    // Two: out at once (status 130), the folder removed all the same.
    let mut server = Server::start("int2")?;
    let folder = server.folders()?.remove(0);
    let held = server.hold_upload()?;
    server.signal("INT")?;
    std::thread::sleep(Duration::from_millis(100));
    server.signal("INT")?;
    let (code, took) = server.wait_exit(Duration::from_secs(10))?;
    assert!(code == Some(130) || code == Some(0), "{code:?}");
    assert!(took < Duration::from_secs(2), "exit took {took:?}");
    assert!(!folder.exists());
    drop(held);
    Ok(())
}

#[test]
fn a_stop_ends_while_a_trainer_tab_has_stopped_reading() -> Result {
    use futures_util::SinkExt;
    use tokio_tungstenite::tungstenite::Message;
    let mut server = Server::start("reader")?;
    let folder = server.folders()?.remove(0);
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    // The tab loads the liver (frames of about 100 kB, 60 per second) and never reads them.
    let tab = rt.block_on(async {
        let (mut tab, _) =
            tokio_tungstenite::connect_async(format!("ws://{}/api/trainer/ws", server.addr))
                .await?;
        let load = tissue_studio::trainer::Command::Load {
            organ: "liver".to_owned(),
        };
        tab.send(Message::Text(serde_json::to_string(&load)?.into()))
            .await?;
        Ok::<_, Box<dyn std::error::Error>>(tab)
    })?;
    // Long enough for the kernel's buffers to fill and a send to block.
    std::thread::sleep(Duration::from_secs(3));
    server.signal("INT")?;
    let (code, took) = server.wait_exit(Duration::from_secs(15))?;
    assert_eq!(code, Some(0));
    assert!(took < Duration::from_secs(6), "exit took {took:?}");
    assert!(!folder.exists());
    drop(tab);
    Ok(())
}

/// A `.vtu` whose points are zlib blocks of zeros: `blocks` MiB once inflated, from about a
/// thousandth of that on the wire, while the piece says it has 4 points.
fn vtu_bomb(blocks: usize) -> Result<Vec<u8>> {
    let block = vec![0u8; 1 << 20];
    let mut enc = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    enc.write_all(&block)?;
    let compressed = enc.finish()?;
    let mut header = Vec::new();
    for v in [blocks as u32, 1 << 20, 1 << 20] {
        header.extend_from_slice(&v.to_le_bytes());
    }
    for _ in 0..blocks {
        header.extend_from_slice(&(compressed.len() as u32).to_le_bytes());
    }
    let mut data = header;
    for _ in 0..blocks {
        data.extend_from_slice(&compressed);
    }
    let mut out = Vec::new();
    write!(
        out,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt32\" compressor=\"vtkZLibDataCompressor\">\n\
         <UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n\
         <Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/></Points>\n\
         <Cells>\n\
         <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>\n\
         <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4</DataArray>\n\
         <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>\n\
         </Cells></Piece></UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_"
    )?;
    out.extend_from_slice(&data);
    out.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
    Ok(out)
}

#[test]
fn a_compressed_vtu_bomb_is_refused_within_100_mib_of_the_baseline() -> Result {
    let server = Server::start("bomb")?;
    // Warm up (the routes, the allocator), then take the baseline.
    let (status, _) = server.request("GET", "/api/organs", "", b"")?;
    assert_eq!(status, 200);
    let baseline = server.status_kb("VmRSS:")?;
    // 1024 blocks: 1 GiB of points (2 GiB widened to f64) from a 1 MiB upload.
    let bomb = vtu_bomb(1024)?;
    assert!(bomb.len() < 2 << 20, "{} bytes", bomb.len());
    let (status, body) = server.request(
        "POST",
        "/api/organs?name=bomb.vtu&unit=cm",
        "Content-Type: application/octet-stream\r\n",
        &bomb,
    )?;
    assert_eq!(status, 400, "{body}");
    let peak = server.status_kb("VmHWM:")?;
    let above = peak.saturating_sub(baseline) as f64 / 1024.0;
    eprintln!(
        "bomb: {} KiB upload, baseline {:.1} MiB, peak {:.1} MiB (+{above:.1} MiB); {body}",
        bomb.len() / 1024,
        baseline as f64 / 1024.0,
        peak as f64 / 1024.0
    );
    assert!(above < 100.0, "peak {above:.1} MiB above the baseline");
    Ok(())
}

/// The restart of the issue, with real processes: a plan saved by one studio is reopened by the
/// next on the same `--data` folder, its report and mesh byte for byte the job's downloads; the
/// folder is private (0700) and the database file too (0600).
#[test]
fn a_plan_saved_is_reopened_by_the_next_process_byte_for_byte() -> Result {
    let mut first = Server::start("restart")?;
    let (status, body) = first.request("POST", "/api/patients?shipped=table2", "", b"")?;
    assert_eq!(status, 200, "{body}");
    let patient: serde_json::Value = serde_json::from_str(&body)?;
    let job = run_short_job(first.addr, &patient["patient"])?;
    let files = ["report.json", "patient.ply", "patient.vtk"];
    let mut originals = Vec::new();
    for file in files {
        let (status, body) =
            first.request("GET", &format!("/api/results/{job}/{file}"), "", b"")?;
        assert_eq!(status, 200, "{file}: {body}");
        originals.push(body);
    }
    let save = serde_json::json!({ "job": job, "name": "five steps" }).to_string();
    let (status, body) = first.request(
        "POST",
        "/api/cases/save",
        "Content-Type: application/json\r\n",
        save.as_bytes(),
    )?;
    assert_eq!(status, 200, "{body}");
    let plan: serde_json::Value = serde_json::from_str(&body)?;
    let uid = plan["uid"].as_str().unwrap_or("").to_owned();
    let data = first.tmp.join("data");
    assert_eq!(mode(&data)?, 0o700, "the library's folder is private");
    assert_eq!(mode(&data.join("cases.sqlite"))?, 0o600, "and its database");
    first.signal("TERM")?;
    let (code, _) = first.wait_exit(Duration::from_secs(10))?;
    assert_eq!(code, Some(0));

    let second = Server::start_in(first.tmp.clone(), &[])?;
    for (file, original) in files.iter().zip(&originals) {
        let (status, body) = second.request(
            "GET",
            &format!("/api/cases/plans/{uid}/files/{file}"),
            "",
            b"",
        )?;
        assert_eq!(status, 200, "{file}");
        assert!(body == *original, "{file} differs after the restart");
    }
    Ok(())
}
